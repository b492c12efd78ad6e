"""The application layer: what a user runs. The ``colosseum`` command (:mod:`app.cli`,
:mod:`app.cli_net`), the runner that drives an engine from a content folder, the Dask
sweep, ``colosseum new``, the experiment commands and the benchmarks (:mod:`app.bench`).

It sits on top of every other layer (docs/ARCHITECTURE.md): it assembles the plugins of
``systems/`` into an application, so nothing below may import it."""
