"""The MuJoCo scene: a plate and a finger whose skin nodes probe it.

Built with ``mujoco.MjSpec`` from the plate's standalone MJCF. The finger's bone slides on
two joints (``slide_x`` along the slide, driven by a velocity actuator; ``press_z`` normal to
the plate, force-controlled). Each skin node is a small sphere on the bone at the pad's
undeformed surface; a collider reports each node's signed distance to the plate (its
penetration-depth map). The skin's elastic response is computed from that map by a skin
model (:mod:`sim_tactile.sim.skin.models`) and applied back to the bone, so MuJoCo integrates the
finger while the skin is quasi-static (its own resonance, above 1 kHz for a few grams of
silicone, lies far above the texture frequencies). The scene also holds ``W``, how the
nodes' loads reach the taxels (:func:`~sim_tactile.scene.elastic.subsurface_weights`).

Two models are compiled from the one spec: ``m_col`` with contacts, used only for collision
queries, and ``m_dyn`` with contacts disabled and without the (massless) node spheres, which
MuJoCo steps. (Inactive "gap" contacts would still be solved as constraints in MuJoCo 4.0,
and static bodies do not collide.)
"""

from __future__ import annotations

import copy
import platform
import warnings
from collections import OrderedDict
from dataclasses import dataclass, field

import mujoco
import numpy as np

from ..cache import register_memo, setup_memo
from ..errors import CacheWarning
from ..hashing import array_digest
from ..plates import Plate
from ..plates import build as build_plate
from ..sensors.layouts import Layout
from ..sensors.pad import Finger
from .elastic import subsurface_weights
from .layered import Stack, layered_subsurface_weights
from .nodes import SkinGrid
from .tractions import shear_subsurface_weights

_T = mujoco.mjtGeom
#: Collision bit of the skin nodes (plates keep bit 1 for other uses).
NODE_BIT = 2
#: Velocity actuator gain of the slide [N s/m] (the arm reacts the skin's drag: the runner
#: records it but does not apply it to the slide joint, so the pad holds its command).
SLIDE_KV = 2000.0
#: Radius of a skin node's probe sphere, as a fraction of the node pitch: the sphere rounds a
#: sharp edge over about this distance, so a node half over an edge feels part of it.
PROBE_RADIUS_FRACTION = 0.25


@dataclass
class Scene:
    """Everything the simulation loop needs, built once per configuration."""

    plate: Plate
    finger: Finger
    grid: SkinGrid
    layout: Layout
    m_col: mujoco.MjModel
    m_dyn: mujoco.MjModel
    node_of_geom: np.ndarray  # (ngeom,) node index of each geom in m_col, -1 if none
    W: np.ndarray  # (M, N) taxel weights of node loads
    jx: int  # dof index of slide_x
    jz: int  # dof index of press_z
    #: the content key of the kept models this scene's are placed copies of (:data:`SCENES`):
    #: what does not move with the placement is the same for every scene of that key
    model_key: str = ""
    #: a finished slide's MjData of a model of this key (:func:`give_back`), which
    #: :meth:`dynamics_data` resets instead of making one
    spare_data: object = field(default=None, repr=False, compare=False)

    @property
    def n_nodes(self) -> int:
        return self.grid.n

    def dynamics_data(self) -> mujoco.MjData:
        """An MjData of ``m_dyn`` in its initial state: the spare one reset (every buffer
        cleared, as a new one is), else a new one."""
        d, self.spare_data = self.spare_data, None
        if d is None:
            return mujoco.MjData(self.m_dyn)
        mujoco.mj_resetData(self.m_dyn, d)
        return d


def taxel_weights(
    grid: SkinGrid,
    layout: Layout,
    finger: Finger,
    slide_dir: tuple[float, float] = (1.0, 0.0),
    cache=None,
) -> np.ndarray:
    """(M, N): the share of each node's load that each taxel reads, in the finger's skin
    (a half-space, or its stack of layers), with the stress of the skin's sliding tractions
    when the finger has them (the pad sliding along ``slide_dir``, a unit vector; slides go
    along +x). Kept in this process by content (:func:`~sim_tactile.cache.setup_memo`): every
    slide of a sensor on a grid reads the same weights; and in ``cache`` (an
    :class:`~sim_tactile.cache.ArtefactCache`), if given, for the next process: the iCub's
    weights take 0.2-0.25 s a grid to compute, each worker of each data set paid them."""
    parts = {
        "xy": array_digest(grid.xy),
        "pitch": [grid.pitch_m, grid.pitch_y_m],
        "taxels": [array_digest(a) for a in (layout.positions, layout.sizes, layout.depth_m)],
        "finger": finger.to_json(),
        "slide_dir": [float(v) for v in slide_dir],
    }
    compute = lambda: (_taxel_weights(grid, layout, finger, slide_dir),)  # noqa: E731
    return setup_memo("taxel weights", parts, compute, (__name__,), cache)[0]


def _taxel_weights(grid, layout, finger, slide_dir) -> np.ndarray:
    args = (grid.xy, grid.pitch_m, layout.positions[:, :2], layout.sizes, layout.depth_m)
    if finger.stack is not None:
        W = layered_subsurface_weights(*args, finger.stack, pitch_y_m=grid.pitch_y_m)
    else:
        W = subsurface_weights(*args, pitch_y_m=grid.pitch_y_m)
    if finger.skin_tractions and finger.friction > 0:
        # the plate's friction on the skin points against the slide, q = -mu p along
        # slide_dir at every node (full sliding); its stress at depth is compressive ahead
        # of the traction (on a layered or compressible skin the tractions also shift the
        # contact pressure: the skin model's coupled compliance, sim.skin)
        stack = finger.stack or Stack.half_space(
            finger.thickness_m, finger.young_pa, finger.poisson
        )
        Wq = shear_subsurface_weights(*args, stack, pitch_y_m=grid.pitch_y_m, direction=slide_dir)
        W = W - finger.friction * Wq
    return W


#: The compiled models a process keeps, by content (:func:`_models`): a worker makes tens of
#: slides of one scene, and composing and compiling its MJCF took a third of a roughness8
#: slide. Least recently used dropped past this many.
SCENES_KEPT = 8
SCENES: OrderedDict[str, tuple] = OrderedDict()
register_memo("compiled scene models", SCENES.clear)


#: The placed copies of kept models that finished slides gave back (:func:`give_back`), with
#: their dynamics' MjData, one set a key of :data:`SCENES`: the next scene of that key places
#: them again instead of copying the kept models (copying and freeing the two models and the
#: data took about 1 ms of a 9 ms pvdf2 slide).
SPARE: OrderedDict[str, tuple] = OrderedDict()
register_memo("placed scene models given back", SPARE.clear)


def give_back(scene: Scene, data: mujoco.MjData) -> None:
    """Keep a finished slide's placed models and its MjData ``data`` of ``scene.m_dyn`` for
    the next scene of their key (:func:`build_scene`). Its runner must not step again: the
    next scene moves the models and resets the data."""
    if not scene.model_key:
        return
    SPARE[scene.model_key] = (scene.m_col, scene.m_dyn, data)
    SPARE.move_to_end(scene.model_key)
    while len(SPARE) > SCENES_KEPT:
        SPARE.popitem(last=False)


def _models(plate, finger, grid, z_damping, node_margin_m, cache) -> tuple:
    """``(m_col, m_dyn, node_of_geom, jx, jz, key)`` of the scene with the bone at the origin
    and MuJoCo's default time step, kept in :data:`SCENES` under the content key of
    everything they depend on: the plate's MJCF artefact (its parameters and the code that
    writes it), the pad, the node grid, the damping, the margin and this module's source;
    and, with ``cache``, in it as MuJoCo's binary models (:data:`MODEL_EXTS`), which a later
    process reads in milliseconds (compiling the iCub's scene took 0.08-0.14 s a plate for
    each worker of each data set). A model read back is the compiled one: its arrays equal
    bit for bit (tested)."""
    from ..hashing import code_version, content_hash
    from ..plates.make.build import artefact_key

    key = content_hash(
        {
            "mjcf": artefact_key(plate, "mjcf"),
            "finger": finger.to_json(),
            "grid": [array_digest(grid.xy), array_digest(grid.z), list(grid.pitch_xy)],
            "z_damping": z_damping,
            "margin": node_margin_m,
            "code": code_version(__name__, libraries=("mujoco",)),
            "machine": platform.machine(),
        }
    )
    kept = SCENES.pop(key, None)
    if kept is None and cache is not None:
        kept = _read_models(cache, key, grid)
    if kept is None:
        kept = _compile_models(plate, finger, grid, z_damping, node_margin_m, cache)
        if cache is not None:
            _write_models(cache, key, kept)
    SCENES[key] = kept
    while len(SCENES) > SCENES_KEPT:
        SCENES.popitem(last=False)
    return (*kept, key)


#: The cache's file kinds of a scene's two compiled models (:func:`_models`): MuJoCo's
#: binary format (``mj_saveModel``), which only the same MuJoCo reads (its version is in the
#: key).
MODEL_EXTS = ("col.mjb", "dyn.mjb")


def _write_models(cache, key: str, kept: tuple) -> None:
    for ext, m in zip(MODEL_EXTS, kept[:2], strict=True):
        buf = np.zeros(mujoco.mj_sizeModel(m), dtype=np.uint8)
        mujoco.mj_saveModel(m, None, buf)
        cache.put(key, ext, buf.tobytes())


def _read_models(cache, key: str, grid: SkinGrid) -> tuple | None:
    """``(m_col, m_dyn, node_of_geom, jx, jz)`` from the binary models stored under ``key``,
    or None where either is not there or cannot be read (then discarded, with a warning)."""
    paths = [cache.get(key, ext) for ext in MODEL_EXTS]
    if any(p is None for p in paths):
        return None
    try:
        m_col, m_dyn = (mujoco.MjModel.from_binary_path(str(p)) for p in paths)
    except (ValueError, OSError) as exc:
        warnings.warn(
            f"cache entry {paths[0].parent.parent} cannot be read as MuJoCo models "
            f"({type(exc).__name__}); they are compiled again",
            CacheWarning,
            stacklevel=3,
        )
        for ext in MODEL_EXTS:
            cache.discard(key, ext)
        return None
    return (m_col, m_dyn, *_model_indices(m_col, m_dyn, grid))


def _model_indices(m_col, m_dyn, grid: SkinGrid) -> tuple:
    """``(node_of_geom, jx, jz)``: the node of each of ``m_col``'s geoms (-1 where none) and
    the dof indices of the slide and the press in ``m_dyn``."""
    node_of_geom = np.full(m_col.ngeom, -1, dtype=np.int64)
    g0 = mujoco.mj_name2id(m_col, mujoco.mjtObj.mjOBJ_GEOM, "node0")
    node_of_geom[g0 : g0 + grid.n] = np.arange(grid.n)
    node_of_geom.flags.writeable = False
    jx = m_dyn.jnt_dofadr[mujoco.mj_name2id(m_dyn, mujoco.mjtObj.mjOBJ_JOINT, "slide_x")]
    jz = m_dyn.jnt_dofadr[mujoco.mj_name2id(m_dyn, mujoco.mjtObj.mjOBJ_JOINT, "press_z")]
    return node_of_geom, int(jx), int(jz)


def add_velocity_servo(spec: mujoco.MjSpec, name: str, joint: str, kv: float) -> None:
    """A velocity servo on ``joint``: force ``kv (ctrl - qvel)`` (the finger's slide, the
    rig's carriage)."""
    spec.add_actuator(
        name=name,
        target=joint,
        trntype=mujoco.mjtTrn.mjTRN_JOINT,
        gaintype=mujoco.mjtGain.mjGAIN_FIXED,
        biastype=mujoco.mjtBias.mjBIAS_AFFINE,
        gainprm=[kv] + [0] * 9,
        biasprm=[0, 0, -kv] + [0] * 7,
    )


def _compile_models(plate, finger, grid, z_damping, node_margin_m, cache) -> tuple:
    xml = build_plate(plate, kinds=("mjcf",), cache=cache).files["mjcf"].read_text()
    spec = mujoco.MjSpec.from_string(xml)
    spec.modelname = f"sim_tactile {plate.name or plate.hash}"
    spec.option.gravity = (0.0, 0.0, 0.0)  # the press force is the applied normal force
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    for g in spec.geoms:  # the plate: collide with skin nodes only
        g.contype = 0
        g.conaffinity = NODE_BIT
    bone = spec.worldbody.add_body(name="bone", pos=(0.0, 0.0, 0.0))
    bone.add_joint(name="slide_x", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=(1, 0, 0))
    bone.add_joint(
        name="press_z", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=(0, 0, 1), damping=z_damping
    )
    px, py = finger.patch_m
    bone.add_geom(
        name="bone",
        type=_T.mjGEOM_BOX,
        size=(px / 2, py / 2, finger.thickness_m / 2),
        pos=(0, 0, finger.thickness_m * 1.5),
        mass=finger.bone_mass_kg,
        contype=0,
        conaffinity=0,
        rgba=(0.85, 0.75, 0.65, 1),
    )
    add_velocity_servo(spec, "slide", "slide_x", SLIDE_KV)
    # the stepped model needs neither contacts nor the massless node spheres, whose poses
    # MuJoCo would otherwise compute every step (30 us a step for a curved pad's 5785 nodes):
    # it is compiled before they are added (deleting them from the spec took 2.5 ms each)
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    m_dyn = spec.compile()
    spec.option.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    r = PROBE_RADIUS_FRACTION * min(grid.pitch_xy)
    for i, ((x, y), z) in enumerate(zip(grid.xy, grid.z, strict=True)):
        bone.add_geom(
            name=f"node{i}",
            type=_T.mjGEOM_SPHERE,
            size=(r, 0, 0),
            pos=(x, y, z + r),
            contype=NODE_BIT,
            conaffinity=0,
            density=0.0,
            group=3,
            margin=node_margin_m,
        )
    m_col = spec.compile()
    return (m_col, m_dyn, *_model_indices(m_col, m_dyn, grid))


def build_scene(
    plate: Plate,
    finger: Finger,
    grid: SkinGrid,
    layout: Layout,
    *,
    dt_s: float,
    x0_m: float,
    z0_m: float,
    z_damping: float,
    y0_m: float = 0.0,
    node_margin_m: float = 0.0,
    slide_dir: tuple[float, float] = (1.0, 0.0),
    cache=None,
) -> Scene:
    """Compose the plate's MJCF with the finger; x0, y0, z0 place the pad's lowest point.
    ``node_margin_m``: the collider reports nodes this far above the plate too (with their
    positive distance); it must be compiled in, as MuJoCo's broad phase sizes its bounding
    boxes from it.

    The compiled models of a plate, pad, node grid, damping and margin are kept in this
    process (:data:`SCENES`, by content) and each slide takes copies, placed at its own start
    and time step: what a slide sets after compiling (the bone's position, the time step) is
    what the compiler would have copied in (the same models, bit for bit, tested)."""
    m_col, m_dyn, node_of_geom, jx, jz, key = _models(
        plate, finger, grid, z_damping, node_margin_m, cache
    )
    spare = SPARE.pop(key, None)
    if spare is None:  # copies of the kept models
        m_col, m_dyn, data = copy.copy(m_col), copy.copy(m_dyn), None
    else:  # a finished slide's copies, placed again
        m_col, m_dyn, data = spare
    m_col, m_dyn = _place(m_col, dt_s, x0_m, y0_m, z0_m), _place(m_dyn, dt_s, x0_m, y0_m, z0_m)
    W = taxel_weights(grid, layout, finger, slide_dir, cache)
    return Scene(
        plate, finger, grid, layout, m_col, m_dyn, node_of_geom, W, int(jx), int(jz), key, data
    )


def dynamics_model(
    plate: Plate,
    finger: Finger,
    grid: SkinGrid,
    *,
    dt_s: float,
    x0_m: float,
    z0_m: float,
    z_damping: float,
    y0_m: float = 0.0,
    node_margin_m: float = 0.0,
    cache=None,
) -> tuple:
    """``(m_dyn, jx, jz)``: the dynamics model of :func:`build_scene`'s scene (the same
    model, bit for bit) without the collision model and the taxels' weights: all a slide
    read wholly off its phase table steps."""
    _, m_dyn, _, jx, jz, _ = _models(plate, finger, grid, z_damping, node_margin_m, cache)
    return _place(copy.copy(m_dyn), dt_s, x0_m, y0_m, z0_m), int(jx), int(jz)


def _place(m, dt_s: float, x0_m: float, y0_m: float, z0_m: float):
    """A copy ``m`` of a kept model set to a slide's time step, its bone at the slide's start
    and offset across the slide (what the compiler would have copied in): the only fields in
    which the copies of one kept model differ."""
    m.opt.timestep = dt_s
    m.body_pos[m.body("bone").id] = (x0_m, y0_m, z0_m)
    return m
