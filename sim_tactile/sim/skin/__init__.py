"""Pressures from depths: the skin models (:mod:`.models`: Winkler, the coupled half-space
or stack, spectral), the contact solvers (:mod:`.contact`), and the solvers on the plate's
own cells: patches clipped at the walls (:mod:`.clipped`) and the lattice anchored to them
(:mod:`.anchored`)."""
