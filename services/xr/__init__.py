"""OpenXR: the headset display, its session, timing, bindings and projection (the
runtime is called from session.py alone; the other modules are pure and tested without
one)."""
