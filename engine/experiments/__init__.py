"""Experiments: a study's design in the content folder (the ``Experiment`` block), the
plan of trials each participant meets, adaptive staircases and the session files.

Pure logic and file I/O (engine core); the plugin that runs trials in the engine is
``systems.experiments``, the commands ``app.experiments.cli`` (``colosseum experiment
run|report|replay``). How to use it: docs/experiments.md.
"""
