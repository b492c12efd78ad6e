"""Content stays in its folder: a hostile script and hostile scene files try every
path-taking entry (``Include``, every file key, ``spawn``, ``require``, a saved
state's ``Content``) with absolute paths, ``..`` and a symlink out of the folder, and
nothing of a marker file outside ever reaches the script or the engine's output."""

from __future__ import annotations

import json
import logging
import shutil
from pathlib import Path

import pytest

from app.cli import main
from engine.confine import OUTSIDE
from engine.scene import check
from engine.scene.schema import ASSET_T, SCHEMAS
from tests.scripting.script_helpers import runtime_of, script_named, scripted_engine

#: What the secret files hold; it must never be seen anywhere.
MARKER = "MARKER-5d1f0c"
SAMPLES = Path(__file__).resolve().parents[1] / "avatars" / "samples"
WALKER = Path(__file__).resolve().parents[2] / "content" / "avatars" / "models" / "walker.glb"

#: (what, the snippet naming FILE): every key of the format that names a file.
FILE_KEYS = {
    "Include": 'Include "FILE"',
    "visual model": 'Object { ID "m" VisualAttributes { Geometry { File "FILE" } } }',
    "physical model": 'Object { ID "m" PhysicalAttributes { Geometry { File "FILE" '
                      'ParseMethod "Box" } } }',
    "texture": 'Object { ID "m" VisualAttributes { Texture "FILE" } }',
    "object sound": 'Object { ID "m" Sound { File "FILE" } }',
    "object script": 'Object { ID "m" Script "FILE" }',
    "contact sound": 'Material { ID "loud" ContactSound "FILE" }',
    "scene sound": 'Sound { ID "s" File "FILE" }',
    "vertex shader": 'VertexShader { ID "v" File "FILE" }',
    "fragment shader": 'FragmentShader { ID "f" File "FILE" }',
    "avatar model": 'Avatar { ID "a" Model "FILE" }',
    "avatar script": 'Avatar { ID "a" Model "walker.glb" Script "FILE" }',
    "scene script": 'Script "FILE"',
    "imported model": 'Model { File "FILE" }',
    "post pass": 'PostPass { ID "p" File "FILE" }',
    "hand contact model": 'Object { ID "m" Hand { Tracker "hand_r" ContactModel "FILE" } }',
    "hand grasp model": 'Object { ID "m" Hand { Tracker "hand_r" GraspModel "FILE" } }',
}
if "NeutralModel" in SCHEMAS["Hand"]:  # (a hand's look at rest, where the schema has it)
    FILE_KEYS["hand neutral model"] = \
        'Object { ID "m" Hand { Tracker "hand_r" NeutralModel "FILE" } }'


@pytest.fixture
def world(tmp_path: Path) -> dict[str, Path]:
    """A content folder and, beside it, a folder of secrets it must not read."""
    outside = tmp_path / "outside"
    outside.mkdir()
    secret = outside / "secret.txt"
    secret.write_text(f"root:x:0:0:{MARKER}:/root\n{MARKER} = 1\nObject {{ ID \"{MARKER}\" }}\n")
    for name in ("secret.obj", "secret.wav", "secret.lua", "secret.png", "secret.glb",
                 "secret.glsl", "secret.scene"):
        shutil.copy(secret, outside / name)
    content = tmp_path / "sim"
    (content / "scripts").mkdir(parents=True)
    shutil.copy(WALKER, content / "walker.glb")  # an avatar whose script is the test
    for ext in (".txt", ".obj", ".wav"):  # inside the folder, pointing out of it
        (content / f"link{ext}").symlink_to(outside / f"secret{ext}")
    return {"content": content, "outside": outside, "secret": secret}


def _hostile_script(targets: list[str]) -> str:
    """A scene script that tries every file key with every target, and ``require`` out."""
    snippets = [form.replace("FILE", target) for target in targets
                for form in FILE_KEYS.values()]
    quoted = ",\n  ".join(json.dumps(snippet) for snippet in snippets)
    return (f"local snippets = {{\n  {quoted}\n}}\n"
            "results = {}\n"
            "function onStart()\n"
            "  for i = 1, #snippets do\n"
            "    local ok, e = pcall(spawn, snippets[i])\n"
            "    results[#results + 1] = tostring(ok) .. ' ' .. tostring(e)\n"
            "  end\n"
            "  local ok, e = pcall(require, '..outside.secret')\n"
            "  results[#results + 1] = tostring(ok) .. ' ' .. tostring(e)\n"
            "end\n")


def test_a_hostile_script_reads_nothing_outside_its_folder(world, caplog, capfd) -> None:
    content, outside = world["content"], world["outside"]
    targets = [str(outside / "secret"), "../outside/secret", "link"]
    targets = [f"{t}{ext}" for t in targets for ext in (".txt", ".obj", ".wav")]
    (content / "scripts" / "hostile.lua").write_text(_hostile_script(targets))
    (content / "main.scene").write_text(
        'Script "scripts/hostile.lua"\nObject { ID "witness" Position [0 0 1] }\n')
    caplog.set_level(logging.DEBUG)
    engine = scripted_engine(content)
    try:
        engine.run(frames=2)
        results = list(script_named(engine, "scripts/hostile.lua").env.results.values())
    finally:
        engine.close()
    assert len(results) == len(targets) * len(FILE_KEYS) + 1
    for result in results:
        assert result.startswith("false "), result  # every attempt refused...
        assert MARKER not in result  # ...without a word of the file
    refusals = [r for r in results if OUTSIDE in r]
    # every name leading out is refused as outside, at the snippet's line and column
    assert len(refusals) == len(targets) * len(FILE_KEYS)
    assert all("<spawn>:1:" in r for r in refusals)
    printed = capfd.readouterr()
    everything = caplog.text + printed.out + printed.err + "\n".join(
        runtime_of(engine).messages)
    assert MARKER not in everything
    assert not any(r.startswith("true") for r in results)


#: Each (block, key) of the schema that names a file, and the FILE_KEYS entries trying it.
TRIED = {("Scene", "Script"): ["scene script"], ("Object", "Script"): ["object script"],
         ("Geometry", "File"): ["visual model", "physical model"],
         ("Visual", "Texture"): ["texture"], ("Sound", "File"): ["object sound", "scene sound"],
         ("Material", "ContactSound"): ["contact sound"], ("Model", "File"): ["imported model"],
         ("VertexShader", "File"): ["vertex shader"],
         ("FragmentShader", "File"): ["fragment shader"], ("PostPass", "File"): ["post pass"],
         ("Avatar", "Model"): ["avatar model"], ("Avatar", "Script"): ["avatar script"],
         ("Hand", "ContactModel"): ["hand contact model"],
         ("Hand", "GraspModel"): ["hand grasp model"],
         ("Hand", "NeutralModel"): ["hand neutral model"]}


def test_every_file_key_of_the_format_is_tried() -> None:
    """The keys tried are the schema's: a key naming a file added later must be tried
    here too (an entry in FILE_KEYS, and one in TRIED)."""
    named = {(block, key) for block, fields in SCHEMAS.items()
             for key, field in fields.items() if field.type == ASSET_T}
    assert named <= set(TRIED), f"not tried: {sorted(named - set(TRIED))}"
    for pair in named:
        assert all(entry in FILE_KEYS for entry in TRIED[pair]), pair


@pytest.mark.parametrize("key", FILE_KEYS)
def test_a_scene_file_naming_a_file_outside_is_an_error_at_its_line(world, key) -> None:
    content = world["content"]
    (content / "main.scene").write_text("// a scene\n" + FILE_KEYS[key].replace(
        "FILE", "../outside/secret.txt") + "\n")
    report = check(content)
    errors = report.errors
    assert errors and errors[0].line == 2 and OUTSIDE in errors[0].message
    assert MARKER not in report.render()


def test_symlinks_and_absolute_paths_out_are_refused_and_allow_path_lets_them_in(
        world, capsys) -> None:
    content, outside = world["content"], world["outside"]
    (outside / "parts.scene").write_text('Object { ID "part" Position [0 0 1] }\n')
    (content / "parts.scene").symlink_to(outside / "parts.scene")
    for name in ("parts.scene", str(outside / "parts.scene")):
        (content / "main.scene").write_text(f'Include "{name}"\n')
        assert main(["check", str(content)]) == 1
        assert OUTSIDE in capsys.readouterr().err
        assert main(["check", str(content), "--allow-path", str(outside)]) == 0
    assert main(["check", str(content), "--allow-path", str(outside / "nope")]) == 2


def test_a_saved_state_must_continue_a_content_folder(world, tmp_path, capsys) -> None:
    state = world["content"] / "state.scene"
    state.write_text('Content "/"\nScript "etc/passwd"\n')
    assert main(["check", str(state)]) == 1
    err = capsys.readouterr().err
    assert "is not a content folder" in err and "root:" not in err


@pytest.mark.parametrize("part", ["images", "buffers"])
def test_model_files_name_nothing_outside_their_folder(world, part) -> None:
    """A glTF's buffers and images lie beside it or below (as trimesh reads an OBJ's)."""
    content = world["content"]
    sample = SAMPLES / "walker_lost_texture.gltf"
    source = json.loads(sample.read_text())
    source[part][0]["uri"] = str(world["secret"])
    shutil.copy(sample.with_suffix(".bin"), content)
    (content / "walker.gltf").write_text(json.dumps(source))
    (content / "main.scene").write_text('Avatar { ID "a" Model "walker.gltf" }\n')
    report = check(content)
    assert any("outside the model's folder" in d.message for d in report.diagnostics)
    assert MARKER not in report.render()
