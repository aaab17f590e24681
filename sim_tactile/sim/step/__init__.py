"""One step of the finger: the held step's interface and its compiled and plain forms
(:mod:`.held`), the held steps on the plate's own cells (:mod:`.plate_held`), the one
function that chooses among them (:mod:`.choose`), the runner that steps MuJoCo
(:mod:`.runner`) and the sample averaging the drivers share (:mod:`.sampling`)."""
