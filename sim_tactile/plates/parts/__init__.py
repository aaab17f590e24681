"""A user's STEP, STL or CadQuery part, or a height-map file, turned into a height-map plate
(:mod:`.user`): the map files (:mod:`.map_files`), a mesh sampled into a map
(:mod:`.mesh_map`, :mod:`.zbuffer`), and the separate CAD process with its time limit
(:mod:`.cad_worker`, :mod:`.cad_run`).

Reading a part builds no artefact: nothing here imports :mod:`sim_tactile.plates.make` or
:mod:`sim_tactile.plates.read`.
"""
