"""A plate's artefacts, cached by their content: the STL and STEP (:mod:`.cad`, and
:mod:`.map_mesh` for a height map), the MuJoCo geometry (:mod:`.mjcf`), the preview
(:mod:`.render`), the build and cache of them all (:mod:`.build`), and the checks that they
agree with the definition (:mod:`.verify`, through a collider probe, :mod:`.probe`).

Make asks the plate's :class:`~sim_tactile.plates.define.surface.Surface` what it is made of
(its features, its profile or its height map); it never tests the texture's kind.
"""
