"""Beyond one machine: an authoritative server, nodes that join it, batch runs.

``colosseum serve`` runs the simulation and publishes each physics frame over ZeroMQ
(:mod:`~services.net.server`); ``colosseum join`` runs a node without physics that
follows it, draws, plays sounds and sends its input back (:mod:`~services.net.client`).
:mod:`~services.net.protocol` is what they say, :mod:`~services.net.codec` how poses are
packed, :mod:`~services.net.keys` the CURVE keys, :mod:`~services.net.follow` how a node
turns frames into the poses it shows. The plugins that tie these to an engine are in
``systems/net.py``.
"""
