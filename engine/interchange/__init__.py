"""Interchange with modelling tools: physical scenes imported from glTF (KHR and OMI physics
extensions, nodes' extras) and Collada (``<physics_scene>``), and exported back as glTF.

:func:`import_model` reads a model file into scene blocks (a :class:`SceneDB`) that the
writer prints as a scene file (``colosseum import``); a scene's ``Model { File
"room.glb" Import 1 }`` is the same blocks, imported when the scene is checked
(:func:`expand_models`). :mod:`.merge` keeps an author's edits when a model is imported
again; :mod:`.export` writes a scene as glTF.

One module per format: :mod:`.gltf_physics`, :mod:`.collada`, :mod:`.extras`; the
format-neutral declarations and their scene blocks are :mod:`.model`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from engine.lazy import lazy_exports

if TYPE_CHECKING:
    from engine.interchange.importer import FORMATS, Imported, import_model, read_model
    from engine.interchange.model import ModelDiagnostic
    from engine.interchange.models import expand_models

__all__ = ["FORMATS", "Imported", "ModelDiagnostic", "expand_models", "import_model",
           "read_model"]

__getattr__, __dir__ = lazy_exports(__name__, {
    "engine.interchange.importer": ("FORMATS", "Imported", "import_model", "read_model"),
    "engine.interchange.model": ("ModelDiagnostic",),
    "engine.interchange.models": ("expand_models",)})
