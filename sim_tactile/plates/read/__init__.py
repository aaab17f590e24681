"""Plates read from (and written to) plate files (:mod:`.files`), and the presets, the plate
files shipped with the package (:mod:`.presets`).

Reading a file builds no artefact: nothing here imports :mod:`sim_tactile.plates.make`.
"""
