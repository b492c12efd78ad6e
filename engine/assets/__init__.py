"""Assets: model, image and sound files, each read once per run by the loader its
extension names, and shared by render, physics shapes and sound.

:class:`Assets` is the one cache (an engine resource: ``Assets.of(engine)``); every
failure is an :class:`AssetError` told the same way, naming the file and the scene line
that asked for it::

    main.scene:12:30: error: cannot load model "rock.obj" (content/x/rock.obj): why

Built in: models through trimesh (.obj .stl .ply .glb .gltf .dae), skinned and animated
models for avatars through pygltflib (.glb .gltf .vrm, :mod:`engine.assets.skinned`), images
through Pillow (.png .jpg .bmp .tga .tif .gif .webp), sounds through libsndfile (.wav .ogg
.flac .aiff); glTF and Collada files also as documents of named nodes
(:mod:`engine.assets.gltf`, :mod:`engine.assets.dae`), whose nodes a scene draws with
``Geometry { File "room.glb" Nodes ["Door"] }`` and importers read. A new format is one
function registered for its extension — put it in a content folder's ``systems/*.py``
(imported before the scene is built) or any module imported before loading. It returns a
:class:`ModelAsset` (:func:`mesh_part` makes a part from raw triangles), an
:class:`ImageAsset` or a ``SoundInfo``; whatever it raises becomes the reason in the
message:

>>> import tempfile
>>> from pathlib import Path
>>> from engine.assets import AssetError, Assets, ModelAsset, mesh_part, register_loader
>>> @register_loader("model", ".tri")
... def load_tri(path):
...     '''One triangle per line: nine numbers.'''
...     rows = [[float(x) for x in line.split()] for line in path.read_text().splitlines()]
...     return ModelAsset(path, (mesh_part([r[i:i + 3] for r in rows for i in (0, 3, 6)],
...                                        [[3 * k, 3 * k + 1, 3 * k + 2]
...                                         for k in range(len(rows))]),))
>>> folder = Path(tempfile.mkdtemp())
>>> _ = (folder / "wedge.tri").write_text("0 0 0  1 0 0  0 1 0\\n")
>>> assets = Assets(folder)
>>> assets.model("wedge.tri").parts[0].faces.tolist()
[[0, 1, 2]]
>>> _ = (folder / "bad.tri").write_text("0 0 zero\\n")
>>> try:
...     assets.model("bad.tri")
... except AssetError as error:
...     print(error.reason)
could not convert string to float: 'zero'
>>> unregister_loader("model", ".tri")
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from engine.assets.registry import (
    KINDS,
    Loader,
    UnknownExtension,
    extensions,
    loader_for,
    register_loader,
    unregister_loader,
)
from engine.assets.service import (
    AssetError,
    Assets,
    Where,
    nodes_name,
    reason,
    split_nodes,
)
from engine.assets.types import ImageAsset, MeshPart, ModelAsset, mesh_part, vertex_normals
from engine.lazy import lazy_exports

if TYPE_CHECKING:
    from engine.assets import dae, gltf, loaders, skinned
    from engine.assets.skinned import AnimationClip, Channel, SkinnedModel, SkinnedPart

__all__ = [
    "KINDS",
    "AnimationClip",
    "AssetError",
    "Assets",
    "Channel",
    "ImageAsset",
    "Loader",
    "MeshPart",
    "ModelAsset",
    "SkinnedModel",
    "SkinnedPart",
    "UnknownExtension",
    "Where",
    "dae",
    "extensions",
    "gltf",
    "loader_for",
    "loaders",
    "mesh_part",
    "nodes_name",
    "reason",
    "register_loader",
    "skinned",
    "split_nodes",
    "unregister_loader",
    "vertex_normals",
]

#: The glTF, Collada and avatar readers load when a scene names such a file (the registry
#: imports them at its first lookup) or when a module imports them.
__getattr__, __dir__ = lazy_exports(__name__, {
    "engine.assets.skinned": ("AnimationClip", "Channel", "SkinnedModel", "SkinnedPart")})
