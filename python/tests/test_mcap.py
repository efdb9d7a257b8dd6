"""McapWriter: the MCAP file for Foxglove from Python. The reference library @mcap/core (node,
tests/mcap/validate_mcap.cjs) reads it, and it holds exactly the messages `ringtrack run --mcap`
writes for the same sequence. Skipped when node or the npm packages are missing."""

import json
import shutil
import subprocess

import pytest
import ringtrack as rt
from conftest import SOURCE_DIR, run_cli

VALIDATOR = SOURCE_DIR / "tests" / "mcap" / "validate_mcap.cjs"


def validate(path):
    if shutil.which("node") is None:
        pytest.skip("node is not installed (the MCAP checks run @mcap/core on node)")
    if not (SOURCE_DIR / "tools" / "mcap-check" / "node_modules" / "@mcap" / "core").exists():
        pytest.skip("the npm packages of tools/mcap-check are not installed (scripts/bootstrap)")
    r = subprocess.run(["node", str(VALIDATOR), str(path)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def run_python(seq, path, **options):
    sequence = rt.Sequence(str(seq))
    config = rt.Config()
    config.set("detection.sensor_height_m", str(sequence.sensor_height_m))  # as `run` does
    pipeline = rt.Pipeline(config, sequence.model)
    with rt.McapWriter(str(path), **options) as mcap:
        for scan, pose, _ in sequence:
            pipeline.process(scan, pose)
            mcap.write(pipeline, scan, pose)
        pipeline.finish()
    return mcap


def test_writes_the_messages_run_writes(simulated_sequence, tmp_path):
    seq, _ = simulated_sequence
    run_cli("run", seq, "--out", tmp_path / "cli", "--quiet", "--no-plots",
            "--mcap", tmp_path / "cli.mcap")
    mcap = run_python(seq, tmp_path / "py.mcap")
    assert mcap.stats["scans"] == 40 and mcap.stats["maps"] == 1
    ours, theirs = validate(tmp_path / "py.mcap"), validate(tmp_path / "cli.mcap")
    assert ours["topics"] == theirs["topics"]
    assert ours["topics"]["/ringtrack/scan"] == 40
    assert ours["decoded"] == theirs["decoded"]  # every cloud, box, id, pose and the map
    assert ours["metadata"]["frame"] == theirs["metadata"]["frame"]
    assert ours["metadata"]["ringtrack"]["command"] == "python"
    assert ours["library"].startswith("ringtrack ")


def test_options_metadata_and_periodic_maps(simulated_sequence, tmp_path):
    seq, _ = simulated_sequence
    sequence = rt.Sequence(str(seq))
    pipeline = rt.Pipeline(rt.Config(), sequence.model)
    mcap = rt.McapWriter(str(tmp_path / "lz4.mcap"), compression="lz4", map_every_scans=10)
    mcap.write_metadata("experiment", {"note": "lz4, maps every 10 scans"})
    for scan, pose, _ in sequence:
        pipeline.process(scan, pose)
        mcap.write(pipeline, scan, pose)
    pipeline.finish()
    mcap.finish()
    j = validate(tmp_path / "lz4.mcap")
    assert j["compression"] == ["lz4"]
    assert j["topics"]["/ringtrack/static_map"] == 4 + 1  # scans 10, 20, 30, 40 and the end
    assert j["metadata"]["experiment"] == {"note": "lz4, maps every 10 scans"}


def test_misuse_is_a_clear_error_and_leaves_no_partial_file(simulated_sequence, tmp_path):
    seq, _ = simulated_sequence
    sequence = rt.Sequence(str(seq))
    scans = [(scan, pose) for scan, pose, _ in sequence][:3]
    pipeline = rt.Pipeline(rt.Config(), sequence.model)
    with pytest.raises(rt.ConfigError, match="compression"):
        rt.McapWriter(str(tmp_path / "bad.mcap"), compression="gzip")
    path = tmp_path / "partial.mcap"
    with pytest.raises(rt.InputError, match="processed last"):
        with rt.McapWriter(str(path)) as mcap:
            pipeline.process(*scans[0])
            mcap.write(pipeline, scans[1][0], scans[1][1])  # not the scan just processed
    assert not path.exists()
    empty = rt.McapWriter(str(tmp_path / "empty.mcap"))
    with pytest.raises(rt.InputError, match="before any scan"):
        empty.finish()
    done = rt.McapWriter(str(tmp_path / "done.mcap"))
    pipeline.process(*scans[2])
    done.write(pipeline, *scans[2])
    done.finish()
    with pytest.raises(RuntimeError, match="closed"):
        done.write(pipeline, *scans[2])
    validate(tmp_path / "done.mcap")


def test_the_foxglove_layout_names_what_the_file_holds(simulated_sequence, tmp_path):
    """config/foxglove_layout.json can only show what the file holds: every topic it names is
    written, with the schema its panel expects, and the scan cloud has the field it colours by
    (nobody here can open Foxglove; this keeps the layout and the sink from drifting apart)."""
    layout = json.loads((SOURCE_DIR / "config" / "foxglove_layout.json").read_text())
    seq, _ = simulated_sequence
    run_python(seq, tmp_path / "layout.mcap")
    written = validate(tmp_path / "layout.mcap")
    schemas = {c["topic"]: c["schema"] for c in written["channels"]}
    named = set()
    for panel_id, panel in layout["configById"].items():
        for topic, settings in panel.get("topics", {}).items():
            named.add(topic)
            if "colorField" in settings:
                assert schemas[topic] == "foxglove.PointCloud", panel_id
                fields = {f["name"] for f in written["decoded"][topic][0]["fields"]}
                assert settings["colorField"] in fields | {"x", "y", "z"}, (topic, fields)
        if "topicPath" in panel:
            named.add(panel["topicPath"].split(".")[0])
    assert named, "the layout names no topic"
    assert named <= set(schemas), named - set(schemas)
    assert {"/ringtrack/scan", "/ringtrack/tracks", "/ringtrack/static_map"} <= named
