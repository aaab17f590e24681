"""What to solve, and on which grid: the slide's protocol (:mod:`.protocol`), the probe rig
(:mod:`.rig`), the fidelity planner (:mod:`.fidelity`) with the errors measured against
physics (:mod:`.measured_errors`), and the lines of the grids that follow the plate's walls
(:mod:`.lattices`). Nothing here loads MuJoCo or numba (an import-linter contract forbids
both, and a test imports the planner in a fresh process), so a slide can be described and
planned without the simulator."""
