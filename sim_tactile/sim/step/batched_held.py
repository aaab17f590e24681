"""The held step of many poses at once on a device (:class:`BatchedHeld`): a phase table's
phases solved together on a GPU.

It is :class:`~.held.PlainHeldStep`'s loop (the depth map at each pose, the height at which
the skin carries the force, a new collision query where a pad moved beyond the collider's
margin), with the spectral skin's force-holding solves of every pose still moving taken in
one batch (:class:`~sim_tactile.sim.skin.contact.batched.BatchedSpectral`, torch). The
collider stays on the CPU: a depth map is a few microseconds, a solve milliseconds. The
answers agree with the plain loop's to the solve's tolerance (the batched solve's FFTs are
torch's; tested in tests/test_sim_batched.py).
"""

from __future__ import annotations

import numpy as np

from ..skin.models import SpectralSkin
from .held import QS_COLLISIONS, PlainHeldStep, _no_height


class BatchedHeld:
    """:class:`~.held.PlainHeldStep` ``hold`` (its skin spectral) stepped for many poses
    at once, its solves batched on ``device`` (``cpu``, ``cuda`` or ``cuda:N``)."""

    def __init__(self, hold: PlainHeldStep, device: str) -> None:
        from ..skin.contact.batched import BatchedSpectral

        if not isinstance(hold, PlainHeldStep) or not isinstance(hold.skin, SpectralSkin):
            raise TypeError("BatchedHeld batches the plain held step of a spectral skin")
        self.hold = hold
        self.device = device
        self.solver = BatchedSpectral(hold.skin, device=device)

    def step_many(
        self, qpos: np.ndarray, jz: int, total: float, taxel_out: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`~.held.PlainHeldStep.step` of each row of ``qpos`` (B, nq), written in
        place (``qpos[:, jz]``, the heights that carry ``total`` [Pa over the nodes]);
        ``taxel_out`` (B, T) receives the taxel loads [N]. Returns ``(force (B,) [N],
        deepest node (B,) [m])``."""
        h = self.hold
        b, n = qpos.shape[0], h.W.shape[1]
        pen = np.zeros((b, n))
        p = np.zeros((b, n))
        moving = np.ones(b, dtype=bool)
        warm = None
        for _ in range(QS_COLLISIONS):
            near = np.zeros(b, dtype=bool)
            for i in np.flatnonzero(moving):
                near[i] = h.collider.depths_at(qpos[i], pen[i])
                if not near[i]:  # nothing near: sink by most of the margin, look again
                    qpos[i, jz] -= 0.9 * h.margin
            solve = np.flatnonzero(moving & near)
            if solve.size:
                start = None if warm is None else warm[solve]
                got, dz, _ = self.solver.solve_force(pen[solve], total, start)
                p[solve] = got
                qpos[solve, jz] -= dz
                pen[solve] += dz[:, None]
                moving[solve[np.abs(dz) <= h.margin]] = False
                warm = p
            if not moving.any():
                break
        else:
            raise _no_height(total * h.area, h.margin)
        loads = p * h.area
        np.matmul(loads, h.W.T, out=taxel_out)
        return loads.sum(axis=1), pen.max(axis=1)


def batched_held(hold, device: str) -> BatchedHeld | None:
    """The batched held step of ``hold`` on ``device``, or None where there is none to batch:
    the CPU (whose own solve is the fastest one pose at a time), or a held step that is not
    the plain loop over a spectral skin (a dense skin's compiled step runs on the CPU)."""
    if device == "cpu":
        return None
    if not isinstance(hold, PlainHeldStep) or not isinstance(hold.skin, SpectralSkin):
        return None
    return BatchedHeld(hold, device)
