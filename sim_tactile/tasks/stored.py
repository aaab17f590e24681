"""A task's data read from a store written by ``sim-tactile generate`` (``run TASK --store``,
``ablate TASK --store``), checked to be what the task would simulate or load itself."""

from __future__ import annotations

from ..datasets.store import StoreError, open_store, parts_of
from ..records import TactileDataset
from .registry import DataRequest, TaskSpec


def task_data(spec: TaskSpec, req: DataRequest) -> TactileDataset:
    """The task's data set: ``spec.get_data(req)``, or, with ``req.store``, the store's data
    set after checking that it was generated for this task with the same quick flag and seed
    (and, for simulated tasks, the same configuration hash and simulating code)."""
    if req.store is None:
        return spec.get_data(req)
    from ..generate import task_slide_config
    from .synthetic import SlideSet

    path = req.store
    st = open_store(path, spec.id if spec.id in parts_of(path) else None)
    cfg = st.config
    if cfg.get("task") != spec.id or bool(cfg.get("quick")) != req.quick:
        raise StoreError(
            f"{st.path} holds {cfg.get('task') or 'a configuration file'}'s "
            f"{'quick ' if cfg.get('quick') else ''}data, not {spec.id}"
            f"{' --quick' if req.quick else ''}: generate it with 'sim-tactile generate "
            f"{spec.id}{' --quick' if req.quick else ''} --out DIR.zarr'"
        )
    if isinstance(spec.get_data, SlideSet):
        want, code = task_slide_config(spec.id, req.quick, req.seed)
        if st.config_hash != want:
            raise StoreError(
                f"{st.path} was generated with another configuration (hash {st.config_hash}, "
                f"{spec.id} with seed {req.seed} is {want}); generate it again"
            )
        if st.meta.get("code_version") != code:
            raise StoreError(
                f"{st.path} was simulated by another version of the simulating code "
                f"({st.meta.get('code_version')}, now {code}); generate it again"
            )
    req.log(f"{spec.id}: reading {len(st)} slides from {st.path} ({st.config_hash})")
    return st.to_tactile()
