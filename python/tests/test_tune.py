"""`ringtrack tune`: the search space file, the figures it reports (checked against numpy and the
benchmark's own groups), studies that resume, local workers, and a PostgreSQL study shared by
two workers, one of them killed."""

import csv
import json
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import numpy as np
import pytest

import ringtrack as rt
from conftest import CLI, SOURCE_DIR
from ringtrack import tuning

optuna = pytest.importorskip("optuna")

# Tiny studies: one scenario, 2 s per run, a few trials.
SMALL = ["--scenarios", "1", "--duration", "2", "--quiet"]


def tune(*args, check=True, **kwargs):
    return subprocess.run([CLI, "tune", *map(str, args)], capture_output=True, text=True,
                          check=check, **kwargs)


def trials(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def write_space(tmp_path, text):
    p = tmp_path / "space.yaml"
    p.write_text(text)
    return p


@pytest.mark.parametrize("text, message", [
    ("parameters:\n  tracking.no_such_key: {type: float, low: 0, high: 1}\n",
     "parameters.tracking.no_such_key: unknown configuration key"),
    ("parameters:\n  tracking.process_noise: {type: float, low: 0.5, high: 0.5}\n",
     "empty range [0.5, 0.5]"),
    ("parameters:\n  tracking.process_noise: {type: float, low: 0.0, high: 1.0, log: true}\n",
     "log range needs low > 0"),
    ("parameters:\n  tracking.confirm_hits: {type: int, low: 1.5, high: 3}\n",
     "must be integers"),
    ("parameters:\n  tracking.confirm_hits: {type: integer, low: 1, high: 3}\n",
     "type 'integer' is not one of"),
    ("parameters:\n  tracking.confirm_hits: {type: int, low: 0, high: 3}\n",
     "outside the key's allowed values"),
    ("parameters:\n  tracking.cost: {type: choice, choices: []}\n", "non-empty list"),
    ("parameters:\n  tracking.confirm_hits: {type: int, low: 1, high: 3, step: 1}\n",
     "unknown field 'step'"),
    ("parameters: {}\n", "nothing to tune"),
    ("params:\n  a: 1\n", "expected a mapping 'parameters"),
])
def test_bad_space_files_name_the_problem(tmp_path, text, message):
    space = write_space(tmp_path, text)
    with pytest.raises(tuning.TuneError, match=None) as e:
        tuning.load_space(space)
    assert message in str(e.value) and str(space) in str(e.value)
    r = tune("--space", space, "--out", tmp_path / "out", *SMALL, check=False)
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and message in r.stderr
    assert not (tmp_path / "out").exists()  # nothing written


def test_shipped_spaces_are_valid():
    space = tuning.load_space(SOURCE_DIR / "config" / "tune_space.yaml")
    keys = {p.key.split(".")[0] for p in space}
    assert keys == {"segmentation", "detection", "tracking"}
    core = tuning.load_space(SOURCE_DIR / "config" / "tune_space_core.yaml")
    full = {p.key: p for p in space}
    assert len(core) == 6
    for p in core:  # a subset of the full space with the same ranges
        assert (p.kind, p.low, p.high, p.log) == (full[p.key].kind, full[p.key].low,
                                                  full[p.key].high, full[p.key].log)


def test_pearson_matches_numpy():
    rng = np.random.default_rng(4)
    x = rng.normal(size=30)
    y = 0.6 * x + rng.normal(size=30)
    assert tuning.pearson(x, y) == pytest.approx(np.corrcoef(x, y)[0, 1], abs=1e-12)
    assert np.isnan(tuning.pearson([1.0], [2.0]))
    assert np.isnan(tuning.pearson([1.0, 1.0], [2.0, 3.0]))


def test_pooled_figures_are_the_benchmarks_groups():
    runs = rt.record_runs(builtins=[2], duration_s=3)
    result = rt.run_cases(runs, rt.Config())
    mine = tuning.pooled(result["cases"])
    group = result["groups"]["overall"]["metrics"]
    assert mine["mota"] == pytest.approx(group["mota"], abs=1e-12)
    assert mine["idf1"] == pytest.approx(group["idf1"], abs=1e-12)


def test_study_writes_outputs_and_resumes(tmp_path):
    out = tmp_path / "study"
    tune("--trials", 3, "--out", out, *SMALL)
    rows = trials(out / "trials.csv")
    assert len(rows) == 3 and {r["state"] for r in rows} <= {"COMPLETE", "PRUNED"}
    best = min((r for r in rows if r["state"] == "COMPLETE"), key=lambda r: float(r["cost"]))
    assert float(best["cost"]) == pytest.approx(1 - float(best["train_mota"]))
    config = rt.Config.load(str(out / "best.yaml"))  # what `run --config` reads
    for key in tuning.load_space(SOURCE_DIR / "config" / "tune_space.yaml"):
        if best[key.key] != "":
            assert float(config.get_text(key.key)) == pytest.approx(float(best[key.key]))
    assert "training MOTA" in (out / "report.md").read_text()
    tune("--trials", 5, "--out", out, *SMALL)  # the same study, two more trials
    again = trials(out / "trials.csv")
    assert len(again) == 5
    assert again[:3] == rows
    (out / "trials.csv").unlink()
    tune("--report", "--out", out, *SMALL)  # outputs only, nothing run
    assert trials(out / "trials.csv") == again
    r = tune("--report", "--study", "nothing-here", "--out", out, *SMALL, check=False)
    assert r.returncode == 2 and "no study 'nothing-here'" in r.stderr


def test_first_trial_runs_the_base_configuration(tmp_path):
    base = tmp_path / "base.yaml"
    base.write_text("tracking:\n  process_noise: 0.37\n  confirm_hits: 3\n")
    space = write_space(tmp_path, "parameters:\n"
                        "  tracking.process_noise: {type: float, low: 0.02, high: 2.0, log: true}\n"
                        "  tracking.confirm_hits: {type: int, low: 1, high: 4}\n"
                        "  detection.min_cluster_points: {type: int, low: 4, high: 6}\n")
    out = tmp_path / "base"
    r = tune("--trials", 3, "--config", base, "--space", space, "--out", out, "--scenarios", "1",
             "--duration", "2")
    # The default min_cluster_points (3) is outside [4, 6]: said, and sampled.
    assert "detection.min_cluster_points lies outside the search space" in r.stderr
    rows = trials(out / "trials.csv")
    assert [r["base"] for r in rows] == ["1", "0", "0"]
    first = rows[0]
    assert float(first["tracking.process_noise"]) == 0.37
    assert int(first["tracking.confirm_hits"]) == 3
    assert 4 <= int(first["detection.min_cluster_points"]) <= 6
    report = (out / "report.md").read_text()
    assert f"Trial 0 ran the base configuration: training MOTA {float(first['train_mota']):.4f}" \
        in report
    best = min((r for r in rows if r["state"] == "COMPLETE"), key=lambda r: float(r["cost"]))
    assert float(best["train_mota"]) >= float(first["train_mota"])
    tune("--trials", 4, "--config", base, "--space", space, "--out", out, *SMALL)  # resumed:
    assert [r["base"] for r in trials(out / "trials.csv")] == ["1", "0", "0", "0"]  # not again
    out = tmp_path / "sampled"
    tune("--trials", 2, "--no-base-trial", "--out", out, *SMALL)
    assert [r["base"] for r in trials(out / "trials.csv")] == ["0", "0"]
    assert "ran the base configuration" not in (out / "report.md").read_text()


def test_loocv_reports_test_mota_and_correlation(tmp_path):
    out = tmp_path / "loocv"
    tune("--trials", 4, "--loocv", "--out", out, *SMALL)
    rows = trials(out / "trials.csv")
    folds = {r["fold"] for r in rows}
    assert folds == {"1-static", "1-moving"}
    report = (out / "report.md").read_text()
    assert "Total test MOTA" in report
    for fold in folds:
        done = [r for r in rows if r["fold"] == fold and r["state"] == "COMPLETE"]
        x = [float(r["train_mota"]) for r in done]
        y = [float(r["test_mota"]) for r in done]
        r_value = np.corrcoef(x, y)[0, 1] if len(done) > 1 and np.std(x) and np.std(y) else None
        if r_value is not None:
            assert f"| {fold} |" in report and f"{r_value:.2f}" in report
        assert (out / f"best-{fold}.yaml").exists()
        base = [r for r in rows if r["fold"] == fold and r["base"] == "1"]
        assert len(base) == 1  # each fold's study started from the defaults once
        best = min(done, key=lambda r: float(r["cost"]))
        assert float(best["train_mota"]) >= float(base[0]["train_mota"])
        assert f"| {float(base[0]['train_mota']):.4f} | {float(base[0]['test_mota']):.4f} |" \
            in report
    assert "The base configuration on the same left-out runs: total test MOTA" in report
    assert (out / "loocv.png").stat().st_size > 1000


def test_sequence_folders_are_tuned_on(tmp_path, simulated_sequence):
    seq, _ = simulated_sequence
    out = tmp_path / "seq"
    tune("--scenarios", "", "--sequences", seq, "--trials", 2, "--out", out, "--quiet")
    rows = trials(out / "trials.csv")
    assert len(rows) == 2
    done = [r for r in rows if r["state"] == "COMPLETE"]
    assert done and all(0 < float(r["train_mota"]) <= 1 for r in done)
    r = tune("--scenarios", "", "--sequences", tmp_path / "missing", "--out", out, "--quiet",
             check=False)
    assert r.returncode == 2 and "missing" in r.stderr
    bare = tmp_path / "bare"  # a sequence without ground truth: one line, the study untouched
    shutil.copytree(seq, bare)
    (bare / "objects.csv").unlink()
    r = tune("--scenarios", "", "--sequences", bare, "--trials", 3, "--out", out, "--quiet",
             check=False)
    assert r.returncode == 2 and "no objects.csv" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr
    tune("--report", "--scenarios", "", "--sequences", seq, "--out", out, "--quiet")
    assert len(trials(out / "trials.csv")) == 2


def test_local_workers_share_one_study(tmp_path):
    out = tmp_path / "workers"
    tune("--trials", 12, "--workers", 2, "--out", out, *SMALL)
    rows = trials(out / "trials.csv")
    finished = [r for r in rows if r["state"] in ("COMPLETE", "PRUNED")]
    # Each worker checks the budget before it starts a trial: at most one extra per worker.
    assert 12 <= len(finished) <= 13
    assert len({r["trial"] for r in rows}) == len(rows)
    assert not any(r["state"] == "RUNNING" for r in rows)
    assert len({r["worker"] for r in rows}) == 2  # both processes did trials


@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_interrupt_then_resume(tmp_path, stop):
    # Ctrl-C and SIGTERM (kill, docker stop) alike: workers stopped, exit 128 + signal, resumable.
    out = tmp_path / "interrupted"
    proc = subprocess.Popen([CLI, "tune", "--trials", "400", "--out", str(out), *SMALL],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    journal = out / "study.journal"
    deadline = time.time() + 60
    while time.time() < deadline and (not journal.exists() or journal.stat().st_size < 4000):
        time.sleep(0.2)
    proc.send_signal(stop)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + stop and "resume" in err and stop.name in err
    # No report was written: run.json says the folder's outputs are not whole.
    status = json.loads((out / "run.json").read_text())
    assert status["complete"] is False and status["state"] == "failed"
    assert stop.name in status["error"] and "resume" in status["error"]
    tune("--trials", 3, "--out", out, *SMALL)  # resumes; the budget is already met or near
    status = json.loads((out / "run.json").read_text())
    assert status["complete"] is True and status["state"] == "finished"
    assert status["command"] == "tune" and status["error"] is None
    rows = trials(out / "trials.csv")
    assert not any(r["state"] == "RUNNING" for r in rows)
    assert len([r for r in rows if r["state"] in ("COMPLETE", "PRUNED")]) >= 3


@pytest.fixture
def postgres():
    if shutil.which("runuser") is None and os.geteuid() == 0:
        pytest.skip("runuser missing")
    if not list(pathlib.Path("/usr/lib/postgresql").glob("*/bin/initdb")):
        pytest.skip("PostgreSQL is not installed (scripts/bootstrap installs it)")
    pytest.importorskip("psycopg2")
    folder = tempfile.mkdtemp(prefix="ringtrack-pg-")
    script = SOURCE_DIR / "scripts" / "pg-throwaway"
    url = subprocess.run([script, "start", folder], capture_output=True, text=True,
                         check=True).stdout.strip()
    yield url
    subprocess.run([script, "stop", folder], check=False)


def worker(url, study, trials, out, *extra):
    return subprocess.Popen([CLI, "tune", "--worker", "--storage", url, "--study", study,
                             "--trials", str(trials), "--out", str(out), *SMALL, *extra])


def test_two_workers_on_postgresql_record_every_trial_once(tmp_path, postgres):
    # A long grace period: on a loaded machine (ctest -j2 beside the heaviest tests) one worker
    # once failed the other's live trial as stale, which then could not record its result
    # ("Trial#5 has already finished"). Stale trials are the next test's subject, not this one's.
    workers = [worker(postgres, "shared", 8, tmp_path / f"w{i}", "--grace", "600")
               for i in range(2)]
    assert [w.wait(timeout=300) for w in workers] == [0, 0]
    study = optuna.load_study(study_name="shared", storage=postgres)
    finished = [t for t in study.trials if t.state.is_finished()]
    assert 8 <= len(finished) <= 9
    assert len({t.number for t in study.trials}) == len(study.trials)
    assert not [t for t in study.trials if t.state == optuna.trial.TrialState.RUNNING]
    assert len({t.user_attrs["worker"] for t in study.trials}) == 2


def running_trials(postgres, study_name):
    try:
        study = optuna.load_study(study_name=study_name, storage=postgres)
    except KeyError:
        return None, []
    return study, [t for t in study.trials if t.state == optuna.trial.TrialState.RUNNING]


def kill_worker_inside_a_trial(tmp_path, postgres, study_name, beat):
    """SIGKILL a worker while one of its trials is RUNNING in the database.

    A kill can land in the short gap between one trial's end and the next one's start; the
    dead worker then leaves nothing running and there is nothing to test. Such a kill is
    retried with a new worker (the study keeps what the last one recorded)."""
    for attempt in range(5):
        victim = worker(postgres, study_name, 400, tmp_path / f"victim{attempt}", *beat)
        deadline = time.time() + 120
        running = []
        while time.time() < deadline and not running:
            time.sleep(0.3)
            study, running = running_trials(postgres, study_name)
            running = running if study is not None and len(study.trials) >= 2 else []
        assert running, "the worker never started a trial"
        victim.send_signal(signal.SIGKILL)
        victim.wait()
        study, left_running = running_trials(postgres, study_name)
        if left_running:
            return study
    pytest.fail("five kills in a row landed between trials")


def test_killed_worker_leaves_no_trial_running(tmp_path, postgres):
    beat = ["--heartbeat", "1", "--grace", "3"]
    study = kill_worker_inside_a_trial(tmp_path, postgres, "killed", beat)
    time.sleep(4)  # past the grace period
    survivor = worker(postgres, "killed", len(study.trials) + 2, tmp_path / "survivor", *beat)
    assert survivor.wait(timeout=300) == 0
    study = optuna.load_study(study_name="killed", storage=postgres)
    assert not [t for t in study.trials if t.state == optuna.trial.TrialState.RUNNING]
    failed = [t for t in study.trials if t.state == optuna.trial.TrialState.FAIL]
    assert failed  # the killed trial was failed by its missing heartbeat...
    retried = [t for t in study.trials if "failed_trial" in t.system_attrs]
    assert retried  # ...and retried by the survivor with the same parameters
    original = study.trials[retried[0].system_attrs["failed_trial"]]
    assert original.state == optuna.trial.TrialState.FAIL
    # A trial killed while it drew its parameters has only some: the retry keeps those.
    assert original.params.items() <= retried[0].params.items()


def test_unreachable_database_is_one_line(tmp_path):
    r = tune("--storage", "postgresql+psycopg2://nobody@/x?host=/nonexistent-socket-dir",
             "--out", tmp_path / "o", *SMALL, check=False)
    assert r.returncode == 2
    assert r.stderr.startswith("ringtrack tune: --storage: cannot reach the database")
    assert r.stderr.count("\n") == 1
