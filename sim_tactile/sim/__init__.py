"""The simulation: the slide protocol (:mod:`.protocol`, no MuJoCo), the fidelity levels,
skin models, colliders, the held step, the runner, :func:`.simulate.simulate` and the static
press. Import the module you need: this package imports nothing, so describing a protocol
does not load MuJoCo."""
