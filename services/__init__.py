"""The services layer: what drives a device or a library for the plugins above it. The
renderer (moderngl), audio (OpenAL Soft), scripting (Lua), input devices, the network
(ZeroMQ), the OpenXR headset, and the glTF exporter (it draws primitives with the
renderer's meshes). It builds on the engine core and knows no plugin: ``systems/`` wires
these into an engine. (The protocols a plugin offers the core, ``SoundControl`` and its
kind, are core: ``engine.services``.)"""
