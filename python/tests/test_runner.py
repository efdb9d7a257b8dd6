"""ringtrack.run (runner::Run) against `ringtrack run`: the same input gives the same files, and
the returned figures are the summary's."""

import pytest

import ringtrack as rt
from conftest import SHARED_DATA, run_cli

# Written by both with the same bytes (timing.csv holds measured times, run.json the CLI's).
SAME_FILES = ["tracks.csv", "poses.txt", "static_map.ply", "static_map.pcd", "config.yaml"]


def test_run_writes_what_the_cli_writes(simulated_sequence, tmp_path):
    seq, cli_out = simulated_sequence
    out = tmp_path / "py"
    summary = rt.run(str(seq), str(out))
    for name in SAME_FILES:
        assert (out / name).read_bytes() == (cli_out / name).read_bytes(), name
    tracks_line = next(line for line in run_cli("run", seq, "--out", tmp_path / "cli2", "--quiet",
                                                 "--no-plots").stdout.splitlines()
                       if line.startswith("tracks "))
    assert tracks_line.split()[1] == str(summary["tracks"])
    scans = sum(1 for _ in (out / "timing.csv").open()) - 1
    assert summary["scans"] == scans == len(summary["total_ms"]) > 0
    assert summary["poses"] == "the sequence's poses.txt"
    assert not summary["stopped"]
    assert not (out / "raw_map.ply").exists()


def test_run_options_reach_the_outputs(simulated_sequence, tmp_path):
    seq, _ = simulated_sequence
    out = tmp_path / "out"
    config = rt.Config()
    config.set("detection.sensor_height_m", 1.9)
    summary = rt.run(str(seq), str(out), config=config, keep_sensor_height=True,
                     filtered_scans=True, raw_map=True, mcap=str(tmp_path / "run.mcap"))
    assert "sensor_height_m: 1.9" in (out / "config.yaml").read_text()
    assert len(list((out / "filtered").glob("*.pcd"))) == summary["scans"]
    assert (out / "raw_map.ply").exists() and (tmp_path / "run.mcap").stat().st_size > 0


def test_run_names_a_missing_input(tmp_path):
    with pytest.raises(rt.InputError, match="nowhere: no such file or folder"):
        rt.run(str(tmp_path / "nowhere"), str(tmp_path / "out"))
    with pytest.raises(rt.InputError, match="--odometry on and --poses exclude each other"):
        rt.run(str(tmp_path), str(tmp_path / "out"), odometry="on", poses="x.tum")


def test_run_a_real_vlp16_capture_with_odometry(tmp_path):
    pcap = SHARED_DATA / "vlp16_indoor_nebula" / "vlp16_dual_4scans.pcap"
    if not pcap.exists():
        pytest.skip(f"{pcap} absent (shared test data)")
    summary = rt.run(str(pcap), str(tmp_path / "out"))
    assert summary["poses"].startswith("odometry")
    assert (tmp_path / "out" / "odometry.csv").exists()
    assert summary["scans"] == len(summary["total_ms"]) >= 2
