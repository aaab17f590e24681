"""The presets as data: plate parameter files and sensor files (TOML).

This folder installs as the package ``sim_tactile.assets``; the code reads the presets from
it. Copy a file, edit it and pass its path where a preset's name goes (``--plate``,
``--sensor``, ``plates`` and ``sensor`` in a configuration file).
"""
