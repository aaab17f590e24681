"""Which solver ``path = auto`` gives a held slide's skin where the node count alone would
choose the dense one (:func:`dense_is_dear`), and where it solves a dense skin at fewer
steps than the dynamics (:func:`dense_step_is_dear`).

The dense solve (:class:`~sim_tactile.sim.skin.contact.ActiveSet`) and the spectral one
(:class:`~sim_tactile.sim.skin.contact.spectral.Spectral`) solve the same discrete problem;
:func:`~.fidelity.solved_spectrally` takes the spectral one above
:data:`~.fidelity.DENSE_MAX_NODES` nodes, where the dense matrices and their factorisation
grow too large. What a dense step costs also depends on the contact set, which the node
count does not see. This module loads neither MuJoCo nor numba.
"""

from __future__ import annotations

from ...plates.define.surface import surface_of
from .fidelity import Fidelity, solved_spectrally
from .measured_errors import node_count
from .options import AUTO_SOLVE_EVERY

#: Fewest nodes of a flat pad's lattice at which ``path = auto`` solves a held slide's skin
#: spectrally where it would be a full dense problem (:func:`dense_is_dear`). A flat pad on
#: flat ground touches with nearly its whole face (the iCub: 2223 of 2835 nodes at 1 N), and
#: every node that leaves the contact set as it rides onto a texture costs an update of
#: |S|^2: the iCub's first steps onto textures20-v1's hemispheres took 0.1-0.4 s each, 3.3 s
#: of a 3.6 s slide. Whole slides of textures20-icub60-v1, dense against spectral at 1e-4
#: (perf/bench_solver.py, slides 1-3, one core): cylinders-4.5mm 4.3-20.6 s against
#: 1.4-2.9 s, hemispheres-6.0mm 3.9-9.0 s against 0.7-0.8 s, the loads within 0.005%.
#: The BioTac's curved pad touches on a patch: its full problems at 2835 nodes stay dense
#: (0.22-0.26 s a slide against 0.63-1.06 s spectral); so do the pads' problems that reduce
#: by column and mirror (the iCub's gratings at 1449 reduced nodes, 1.9-3.6 s against
#: 3.0-4.9 s at the reference tolerance). finger7's bumps on grid3x3's flat pad (at
#: a5d399a): 2401 nodes 9.6 s dense against 6.5 s, 1089 nodes 0.9 s against 3.1 s.
FLAT_SPECTRAL_MIN_NODES = 2000


def dense_is_dear(fid: Fidelity, finger, by_column: bool) -> bool:
    """Whether ``auto`` solves a held slide's skin spectrally though it would be solved
    densely (:func:`~.fidelity.solved_spectrally`): a flat pad of at least
    :data:`FLAT_SPECTRAL_MIN_NODES` nodes on its own lattice, whose depths do not reduce by
    column (``by_column``: :func:`~.phase.depths_by_column`), and whose skin the spectral
    solve takes. Both solve the same discrete problem; see the constant for the costs."""
    if by_column or finger.shape != "flat":
        return False
    if solved_spectrally(fid, finger) or not solved_spectrally(fid, finger, "spectral"):
        return False
    return node_count(finger, fid.pitch_m, fid.pitch_y_m) >= FLAT_SPECTRAL_MIN_NODES


def smooth_relief(plate) -> bool:
    """Whether a dear dense skin that ``auto`` solves spectrally (:func:`dense_is_dear`) is
    also solved at every :data:`~.options.AUTO_SOLVE_EVERY`-th step only: on a texture of
    hemispherical caps, where a pressed pad meets no vertical wall and its loads change
    smoothly along the slide. Measured against the per-step solve on textures20-icub60-v1
    (relative L2 of the taxel loads over a slide): hemispheres-6.0mm 0.29-0.46% (slides
    1-3), and at every 2nd step on the caps of 3.0 and 4.5 mm 0.64-0.67% and 0.38%; where
    the bumps are cylinders, with walls, 1.08-2.02% on cylinders-4.5mm, past the 2% that
    ``auto`` allows: those keep every step."""
    return surface_of(plate).all_caps


def dense_step_is_dear(fid: Fidelity, finger, by_column: bool, spectral: bool) -> bool:
    """Whether ``auto`` solves a held slide's dense skin at every
    :data:`~.options.AUTO_SOLVE_EVERY`-th step only: the coupled half-space or layered skin
    on the pad's own lattice (not the plate-anchored lattice, nor clipped patches, nor L0's
    Winkler bed), solved densely (not ``spectral``) as a full problem (its depths do not
    reduce by column: ``by_column``), where a sample spans at least that many steps. Its
    step is then a block update of the contact set's inverse on most steps (multilayer3-v1's
    hemispheres: 326 us a step, 6.4 of a set's 9.3 s). See
    :data:`~.options.AUTO_SOLVE_EVERY` for the measured errors."""
    if spectral or by_column or not fid.coupled or fid.clipped or fid.wall_m is not None:
        return False
    return fid.steps_per_sample >= AUTO_SOLVE_EVERY


__all__ = ["FLAT_SPECTRAL_MIN_NODES", "dense_is_dear", "dense_step_is_dear"]
