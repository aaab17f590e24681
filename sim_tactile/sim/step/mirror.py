"""A held step's answer mirrored along the slide (:func:`mirrored_loads`).

Where the plate is mirror symmetric about a pad position ``c`` along the slide
(:func:`~sim_tactile.sim.plan.phase.mirror_centre`) and the pad is symmetric too (each skin
node has its image across the pad's centre line ``x = 0``, at the same y and height, of the
same radius and margin), the held problem of the pad at ``2 c - x`` is the mirror image of
the one at ``x``: its node pressures are the first's, each at its image node, and its
force, height and deepest node the same. Its taxel loads are then the taxel weights applied
to the mirrored pressures: a phase table solves half a period and reads the other half off
these (:func:`~.phase_table.tabulate`).

The skin must be symmetric under the mirror: the spectral and Winkler skins are (their
response depends on distances alone); a dense compliance is checked on a spread of its
rows (:data:`CHECKED_ROWS`; a skin whose sliding friction enters its normal problem leans
along the slide in every row, and fails).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..skin.models import CoupledSkin
from .held import _SYM_RTOL, CompiledHeldStep, PlainHeldStep

#: Rows of a dense compliance compared with their mirror images, spread evenly over the
#: nodes (the whole matrix, 2835 nodes of the iCub's and the BioTac's pads, took 0.25 s a
#: worker to gather; these take under a millisecond).
CHECKED_ROWS = 64


def mirror_symmetric(C: np.ndarray, image: np.ndarray) -> bool:
    """Whether the compliance ``C`` is unchanged by the node mirror ``image`` on
    :data:`CHECKED_ROWS` rows spread over it (each whole), to the mirror-halved step's
    tolerance."""
    rows = np.unique(np.linspace(0, len(image) - 1, CHECKED_ROWS).round().astype(np.int64))
    a = C[rows][:, image]
    return bool(np.allclose(C[image[rows]], a, rtol=_SYM_RTOL, atol=0.0))


def node_images(local: np.ndarray, radius: np.ndarray, margin: np.ndarray) -> np.ndarray | None:
    """Each node's image across ``x = 0`` (its x negated, the same y, z, radius and margin,
    bit for bit), or None where some node has none. ``local`` (n, 3) the nodes' positions
    on the bone."""
    rows = np.column_stack([local, radius, margin]).astype(np.float64)
    rows = rows + 0.0  # -0.0 -> 0.0: the centre line maps to itself
    image = rows.copy()
    image[:, 0] = -image[:, 0] + 0.0
    order = np.lexsort(rows.T[::-1])
    at = np.lexsort(image.T[::-1])
    if not np.array_equal(rows[order], image[at]):
        return None
    out = np.empty(len(rows), dtype=np.int64)
    out[at] = order  # image of node at[i] is the node order[i]
    return out


def mirrored_loads(hold, collider, skin) -> Callable[[np.ndarray], None] | None:
    """``write(taxel_out)``: the taxel loads [N] of the mirror image of ``hold``'s last
    step, written into ``taxel_out``; None where the step, the pad or the skin has no such
    image (a step over the plate's own cells, an asymmetric pad or node grid, a compliance
    that the mirror changes) or where the image was measured to serve worse than the whole
    period (a dense step over ridges across the whole pad, below)."""
    if not isinstance(hold, PlainHeldStep | CompiledHeldStep):
        return None
    if isinstance(hold, CompiledHeldStep) and hold.columns:
        # ridges across the whole pad, on a dense step that solves one node a column: a
        # column steps onto a ridge all at once, and where a row of nodes meets a wall the
        # held height it settles to depends on the side the pad came from, which an image
        # reverses. Measured on the BioTac's textures20-v2 gratings (two slides each, against
        # the per-step solve): the mirrored tables 0.47-2.16% (relative L2), the whole
        # period's 0.32-1.75%; on every other plate of the BioTac and the iCub the mirror
        # was as close or closer
        return None
    image = node_images(collider.local, collider.radius, collider.margin)
    if image is None:
        return None
    if isinstance(skin, CoupledSkin) and not mirror_symmetric(skin.C, image):
        return None
    if isinstance(hold, PlainHeldStep):
        if image.size != hold.W.shape[1]:
            return None

        def write_plain(out: np.ndarray) -> None:
            np.matmul(hold.W, hold.p[image] * hold.area, out=out)

        return write_plain
    full_to_reduced = np.full(image.size, -1, dtype=np.int64)
    full_to_reduced[hold.nodes] = np.arange(hold.nodes.size)
    reduced = full_to_reduced[image[hold.nodes]]
    if (reduced < 0).any():
        return None

    def write_compiled(out: np.ndarray) -> None:
        np.matmul(hold.W, hold.f[reduced] * hold.area, out=out)

    return write_compiled
