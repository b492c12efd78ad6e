"""The scene benchmark runs end to end (its timings are reported by `colosseum bench scene`)."""

from engine.scene import bench_scene, check, generate_scene


def test_bench_scene_reports_sizes_and_phases(tmp_path):
    r = bench_scene(50)
    assert r["objects"] == 50 and r["entities"] == 50 and r["file_bytes"] > 50 * 100
    assert {"parse_s", "build_specs_s", "instantiate_s", "total_s"} <= set(r)


def test_generated_scene_is_clean(tmp_path):
    (tmp_path / "main.scene").write_text(generate_scene(30))
    assert check(tmp_path).diagnostics == []
