"""What a plate is, and its surface: the plate and its texture's parameters (:mod:`.spec`),
the raised features' shapes (:mod:`.geometry`), the texture's scales (:mod:`.scales`) and
the one :class:`~.surface.Surface` per kind of texture (:mod:`.surface`), the one place that
tells the kinds apart.

The definition reads no file, knows no user's part and builds nothing: it imports none of
the other three folders (``pyproject.toml``'s plates contract).
"""
