"""`ringtrack tune` (also `python3 -m ringtrack.tune`): the paper's parameter optimisation
(section IV.C) with Optuna's Tree of Parzen Estimators: cost 1 - MOTA (paper mode) of the
training runs, optional leave-one-out cross-validation with the Pearson correlation between
training and test MOTA (Fig. 5), on one machine (--workers) or many (--storage postgresql://).
See docs/tuning.md."""

import argparse
import math
import os
import pathlib
import random
import signal
import socket
import subprocess
import sys
import time

from . import _ringtrack as rt
from . import config_dir
from . import tuning
from .tuning import TuneError

EXIT_BAD_INPUT = 2
EXIT_INTERRUPTED = 128  # + the signal: 130 for Ctrl-C (SIGINT), 143 for SIGTERM
# The signal that stopped the tuner; SIGTERM (kill, docker stop, systemd) is handled as Ctrl-C.
_stopped_by = [signal.SIGINT]


# Inside Optuna's optimize loop but outside a trial's objective (its sampler, its bookkeeping
# after a trial, the callbacks), an interrupt waits: Optuna 3.1 is not safe against one there (a
# KeyboardInterrupt inside its tell of a finished trial ended in an UnboundLocalError and exit 1,
# not 130). It is raised where it is safe: at once inside an objective (Optuna marks the trial
# failed and raises it on), at the next trial's start, or when the optimize loop returns.
_optuna_busy = [False]
_pending = [False]


def _interrupt(signum, _frame):
    _stopped_by[0] = signum
    if _optuna_busy[0]:
        _pending[0] = True
        return
    raise KeyboardInterrupt


def _raise_if_pending():
    if _pending[0]:
        raise KeyboardInterrupt


def _guarded(objective):
    """The objective with interrupts raised at once while it runs, and a waiting one first."""
    def run(trial):
        _optuna_busy[0] = False
        try:
            _raise_if_pending()
            return objective(trial)
        finally:
            _optuna_busy[0] = True
    return run


def _optimize_guarded(study, objective, callbacks):
    _optuna_busy[0] = True
    try:
        study.optimize(_guarded(objective), callbacks=callbacks)
    finally:
        _optuna_busy[0] = False
    _raise_if_pending()


def interrupted_status():
    return EXIT_INTERRUPTED + _stopped_by[0]


def parse_args(argv):
    p = argparse.ArgumentParser(
        prog="ringtrack tune",
        description="Tune the pipeline's parameters on simulated scenarios (Optuna TPE; "
        "docs/tuning.md).")
    p.add_argument("--space", default=os.path.join(config_dir, "tune_space.yaml"),
                   help="search space YAML (default: config/tune_space.yaml)")
    p.add_argument("--trials", type=int, default=50,
                   help="completed trials per study (per fold with --loocv); default 50")
    p.add_argument("--scenarios", default="1,2,3,4,5,6,7",
                   help="built-in scenarios, comma separated (default all seven); '' for none")
    p.add_argument("--scenario-files", nargs="*", default=[],
                   help="scenario files (YAML) to tune on as well; never the validation set "
                   "you report on")
    p.add_argument("--sequences", nargs="*", default=[],
                   help="sequence folders with objects.csv (ringtrack simulate / convert output "
                   "plus ground truth) to tune on as well, read once")
    p.add_argument("--sensors", choices=("both", "static", "moving"), default="both",
                   help="sensor motions per scenario (default both: 14 runs for the built-ins)")
    p.add_argument("--duration", type=float, default=30.0,
                   help="seconds simulated per run (default 30)")
    p.add_argument("--seed", type=int, default=1, help="simulator seed and sampler seed")
    p.add_argument("--sampler", choices=("tpe", "hyperopt", "random"), default="tpe",
                   help="tpe: Optuna's TPE defaults; hyperopt: TPE with hyperopt 0.1.2's "
                   "settings (equivalent, not hyperopt itself); random: a baseline")
    p.add_argument("--objectives", default="mota",
                   help="comma-separated costs: mota (1 - MOTA, always first), idf1 (1 - IDF1), "
                   "ms (pipeline ms per scan)")
    p.add_argument("--loocv", action="store_true",
                   help="leave-one-out: per run, tune on the others and score the left-out one")
    p.add_argument("--no-base-trial", action="store_true",
                   help="do not start each study with the base configuration's values (by "
                   "default its first trial runs them, so the best is never worse on the "
                   "training runs than the base)")
    p.add_argument("--workers", type=int, default=1,
                   help="processes on this machine sharing the study (default 1)")
    p.add_argument("--storage", default="",
                   help="postgresql://USER@HOST/DB (several machines), sqlite:///FILE, or "
                   "journal:FILE (default: journal:OUT/study.journal)")
    p.add_argument("--study", default="ringtrack", help="study name (default ringtrack)")
    p.add_argument("--config", default="", help="base configuration YAML the trials start from")
    p.add_argument("--out", default="tune", help="output folder (default tune)")
    p.add_argument("--heartbeat", type=float, default=10.0,
                   help="database storages: seconds between a running trial's heartbeats")
    p.add_argument("--grace", type=float, default=60.0,
                   help="database storages: a trial without heartbeat this long is failed and "
                   "retried")
    p.add_argument("--worker", action="store_true",
                   help="join the study and optimise only (no report): what --workers starts, "
                   "and what to start on other machines")
    p.add_argument("--report", action="store_true",
                   help="write the outputs from the study as it stands (no trials, no "
                   "simulation): for a study other machines are running, or an unfinished one")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    a = p.parse_args(argv)
    if a.trials < 1:
        p.error("--trials must be at least 1")
    if a.workers < 1:
        p.error("--workers must be at least 1")
    if not a.duration > 0:
        p.error("--duration must be > 0")
    return a


def log(args, text):
    if not args.quiet:
        print(f"ringtrack tune: {text}", file=sys.stderr, flush=True)


def objectives_of(args):
    names = [n.strip() for n in args.objectives.split(",") if n.strip()]
    if not names or names[0] != "mota":
        raise TuneError(f"--objectives: '{args.objectives}': the first objective must be mota")
    for n in names:
        if n not in tuning.OBJECTIVES:
            raise TuneError(f"--objectives: unknown objective '{n}' (mota, idf1, ms)")
    if len(set(names)) != len(names):
        raise TuneError(f"--objectives: '{args.objectives}' names an objective twice")
    return names


def builtins_of(args):
    if not args.scenarios.strip():
        return []
    try:
        numbers = [int(s) for s in args.scenarios.split(",")]
    except ValueError:
        raise TuneError(f"--scenarios: '{args.scenarios}': expected numbers 1-7, comma "
                        "separated") from None
    bad = [n for n in numbers if not 1 <= n <= 7]
    if bad:
        raise TuneError(f"--scenarios: no built-in scenario {bad[0]} (1-7)")
    return numbers


def base_config_yaml(args):
    config = rt.Config.load(args.config) if args.config else rt.Config()
    return config.to_yaml()


def make_storage(args, out):
    """The Optuna storage; raises TuneError when a database cannot be reached (nothing is
    written then)."""
    import optuna

    url = args.storage or f"journal:{out / 'study.journal'}"
    if url.startswith("journal:"):
        path = url[len("journal:"):]
        if args.report and not os.path.exists(path):
            raise TuneError(f"--report: {path}: no such study journal")
        tuning.ensure_dir(pathlib.Path(path).parent)
        from optuna.storages import JournalFileStorage, JournalStorage

        try:
            return JournalStorage(JournalFileStorage(path))
        except OSError as e:
            raise TuneError(f"{path}: cannot open the study journal: {e.strerror}") from None
    if not url.startswith(("postgresql", "sqlite", "mysql")):
        raise TuneError(f"--storage: '{url}': expected postgresql://..., sqlite:///... or "
                        "journal:FILE")
    from optuna.storages import RDBStorage, RetryFailedTrialCallback
    from sqlalchemy.exc import IntegrityError, ProgrammingError

    for attempt in range(4):
        try:
            return RDBStorage(url, heartbeat_interval=max(1, int(args.heartbeat)),
                              grace_period=max(2, int(args.grace)),
                              failed_trial_callback=RetryFailedTrialCallback(max_retry=3))
        except (IntegrityError, ProgrammingError):
            # Workers that start together on a new database race to create Optuna's tables;
            # the losers see a duplicate and find the tables there when they try again.
            if attempt == 3:
                raise
            time.sleep(0.5 + random.random())
        except Exception as e:  # SQLAlchemy's errors carry the driver's message
            first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
            raise TuneError(f"--storage: cannot reach the database at {url}: {first}") from None


def make_sampler(args, worker_index):
    import optuna

    seed = args.seed * 1000 + worker_index  # workers must not draw the same start points
    if args.sampler == "random":
        return optuna.samplers.RandomSampler(seed=seed)
    if args.sampler == "hyperopt":
        return optuna.samplers.TPESampler(**optuna.samplers.TPESampler.hyperopt_parameters(),
                                          seed=seed)
    return optuna.samplers.TPESampler(seed=seed)


class Progress:
    """Trial, cost, best so far and the time left, one line per finished trial."""

    def __init__(self, args, fold, total):
        self.args, self.fold, self.total, self.start = args, fold, total, time.monotonic()
        self.done_here = 0

    def __call__(self, study, trial):
        import optuna

        self.done_here += 1
        states = (optuna.trial.TrialState.COMPLETE, optuna.trial.TrialState.PRUNED)
        done = len(study.get_trials(deepcopy=False, states=states))
        best = tuning.best_trial(study)
        per_trial = (time.monotonic() - self.start) / self.done_here
        left = max(0, self.total - done) * per_trial / max(1, self.args.workers)
        cost = f"{trial.values[0]:.4f}" if trial.values else trial.state.name.lower()
        best_text = f"{best.values[0]:.4f} (MOTA {1 - best.values[0]:.3f})" if best else "-"
        extra = ""
        if "test_mota" in trial.user_attrs:
            extra = f", test MOTA {trial.user_attrs['test_mota']:.3f}"
        log(self.args, f"{self.fold}: trial {done}/{self.total} cost {cost}{extra}, best "
            f"{best_text}, about {left / 60:.1f} min left")


def folds_of(runs, loocv):
    if not loocv:
        return [("all", runs, None)]
    if len(runs) < 2:
        raise TuneError("--loocv needs at least two runs")
    return [(r.stem, [o for o in runs if o is not r], r) for r in runs]


def study_name(args, fold):
    return args.study if fold == "all" else f"{args.study}/loo-{fold}"


def settings_of(args):
    """What defines a study's runs and trials, stored with it so that reports say what ran."""
    return {"sampler": args.sampler, "trials": args.trials, "objectives": args.objectives,
            "seed": args.seed, "scenarios": args.scenarios, "scenario_files": args.scenario_files,
            "sequences": [str(s) for s in args.sequences], "sensors": args.sensors,
            "duration": args.duration, "space": args.space}


def optimise(args, storage, folds, space, base_yaml, objectives, worker_index, base=None):
    """Runs each fold's study to args.trials finished trials. base: the parameters the main
    process enqueues as a study's first trial (once per study; workers pass None)."""
    import optuna
    from optuna.study import MaxTrialsCallback

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    directions = [tuning.OBJECTIVES[n][0] for n in objectives]
    worker = f"{socket.gethostname()}:{os.getpid()}"
    states = (optuna.trial.TrialState.COMPLETE, optuna.trial.TrialState.PRUNED)
    for fold, train, test in folds:
        study = optuna.create_study(study_name=study_name(args, fold), storage=storage,
                                    sampler=make_sampler(args, worker_index),
                                    directions=directions, load_if_exists=True)
        if "settings" not in study.user_attrs:
            study.set_user_attr("settings", settings_of(args))
        if len(study.get_trials(deepcopy=False, states=states)) >= args.trials:
            continue
        if base:  # none when every key's base value lies outside the space
            study.enqueue_trial(base, user_attrs={"base": True}, skip_if_exists=True)
        objective = tuning.Objective(space, train, test, base_yaml, objectives, worker)
        _optimize_guarded(study, objective, [MaxTrialsCallback(args.trials, states=states),
                                             Progress(args, fold, args.trials)])


def study_names_in(storage, args):
    """The names of this study and its LOOCV folds that exist in the storage."""
    import optuna

    return [s.study_name for s in optuna.get_all_study_summaries(storage)
            if s.study_name == args.study or s.study_name.startswith(args.study + "/loo-")]


def fail_trials_of(storage, names, worker_label_=None):
    """Marks RUNNING trials FAIL (those of one dead worker, or all of an earlier session of a
    local journal) and queues their parameters again, so none stays stuck and none is lost."""
    import optuna

    failed = 0
    for name in names:
        study = optuna.load_study(study_name=name, storage=storage)
        for t in study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.RUNNING,)):
            if worker_label_ is not None and t.user_attrs.get("worker", "") != worker_label_:
                continue
            storage.set_trial_state_values(t._trial_id, optuna.trial.TrialState.FAIL)
            if t.params:
                study.enqueue_trial(t.params, user_attrs={"retry_of": t.number})
            failed += 1
    return failed


def start_workers(args, argv, count):
    children = []
    for i in range(count):
        cmd = [sys.executable, "-m", "ringtrack.tune", *argv, "--worker"]
        env = dict(os.environ, RINGTRACK_TUNE_WORKER_INDEX=str(i + 1))
        children.append(subprocess.Popen(cmd, env=env))
    return children


def stop_workers(children):
    """Interrupts the workers (their running trials end FAIL and are redone on resume)."""
    for child in children:
        if child.poll() is None:
            child.send_signal(signal.SIGINT)
    for child in children:
        child.wait()


def worker_label(pid):
    return f"{socket.gethostname()}:{pid}"


def reap(args, storage, children):
    """Waits for the worker processes; a worker that died leaves no RUNNING trial behind."""
    for child in children:
        code = child.wait()
        if code != 0:
            n = fail_trials_of(storage, study_names_in(storage, args), worker_label(child.pid))
            log(args, f"worker {child.pid} exited with {code}; {n} running trial(s) failed and "
                "queued again")


def write_outputs(args, out, storage, folds, base_yaml, space):
    import optuna

    studies = {fold: optuna.load_study(study_name=study_name(args, fold), storage=storage)
               for fold, _, _ in folds}
    tuning.write_trials_csv(out / "trials.csv", studies)
    first = next(iter(studies.values()))
    st = first.user_attrs.get("settings", settings_of(args))  # as the study was run
    lines = ["# ringtrack tune", "",
             f"- ringtrack {rt.__version__}, sampler {st['sampler']}, {st['trials']} trials per "
             f"study, objectives {st['objectives']}, seed {st['seed']}",
             f"- runs: scenarios {st['scenarios'] or 'none'}"
             f"{' + ' + ', '.join(st['scenario_files']) if st['scenario_files'] else ''}, "
             f"sensors {st['sensors']}, {st['duration']:g} s each"
             f"{'; sequences ' + ', '.join(st['sequences']) if st['sequences'] else ''}",
             f"- search space: {st['space']} ({len(space)} keys)", ""]
    if args.loocv:
        lines += loocv_report(args, out, studies, folds, base_yaml)
    else:
        lines += single_report(args, out, studies["all"], base_yaml, space)
    (out / "report.md").write_text("\n".join(lines) + "\n", encoding="utf-8")


def single_report(args, out, study, base_yaml, space):
    best = tuning.best_trial(study)
    if best is None:
        return ["No trial completed."]
    config = tuning.config_for(best.params, base_yaml)
    (out / "best.yaml").write_text(config.to_yaml(), encoding="utf-8")
    default = rt.Config.from_yaml(base_yaml)
    lines = [f"Best of {len(study.trials)} trials: trial {best.number}, training MOTA "
             f"{best.user_attrs['train_mota']:.4f} (cost {best.values[0]:.4f}), IDF1 "
             f"{best.user_attrs['train_idf1']:.4f}, {best.user_attrs['ms_per_scan']:.3f} ms "
             "per scan.", ""]
    base = tuning.base_trial(study)
    if base is not None:
        lines += [f"Trial {base.number} ran the base configuration: training MOTA "
                  f"{base.user_attrs['train_mota']:.4f}.", ""]
    lines += ["`best.yaml` holds the whole configuration (`ringtrack run --config best.yaml`).",
              "", "| key | base | best |", "| --- | ---: | ---: |"]
    for p in space:
        value = best.params[p.key]
        shown = f"{value:.4g}" if isinstance(value, float) else str(value)
        lines.append(f"| {p.key} | {default.get_text(p.key)} | {shown} |")
    return lines


def loocv_report(args, out, studies, folds, base_yaml):
    import optuna  # noqa: F401

    lines = ["## Leave-one-out cross-validation", "",
             "Per fold: tuned on every other run, the best trial (lowest training cost) scored "
             "on the left-out run; r = Pearson correlation of training and test MOTA over the "
             "fold's trials (the paper's Fig. 5). The base columns are the fold's trial that ran "
             "the base configuration (none with --no-base-trial).", "",
             "| left out | trials | best training MOTA | test MOTA | base training MOTA | "
             "base test MOTA | r |", "| --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
    correlations, errors, gt = {}, 0.0, 0
    base_errors, base_gt = 0.0, 0
    for fold, _, _ in folds:
        study = studies[fold]
        best = tuning.best_trial(study)
        xs, ys, r = tuning.fold_correlation(study)
        correlations[fold] = (xs, ys, r)
        if best is None:
            lines.append(f"| {fold} | {len(study.trials)} | - | - | - | - | - |")
            continue
        config = tuning.config_for(best.params, base_yaml)
        (out / f"best-{fold}.yaml").write_text(config.to_yaml(), encoding="utf-8")
        a = best.user_attrs
        errors += a["test_errors"]
        gt += a["test_gt"]
        base = tuning.base_trial(study)
        base_text = "- | -"
        if base is not None:
            b = base.user_attrs
            base_errors += b["test_errors"]
            base_gt += b["test_gt"]
            base_text = f"{b['train_mota']:.4f} | {b['test_mota']:.4f}"
        lines.append(f"| {fold} | {len(study.trials)} | {a['train_mota']:.4f} | "
                     f"{a['test_mota']:.4f} | {base_text} | {r:.2f} |")
    total = 1 - errors / gt if gt else float("nan")
    finite = sorted(r for _, _, r in correlations.values() if math.isfinite(r))
    median_r = finite[len(finite) // 2] if finite else float("nan")
    lines += ["", f"**Total test MOTA** (the left-out runs' summed counts, each scored with its "
              f"fold's best configuration): **{total:.4f}**; median r {median_r:.2f} "
              f"(range {finite[0]:.2f} to {finite[-1]:.2f})." if finite else
              f"**Total test MOTA**: **{total:.4f}**.", ""]
    if base_gt:
        lines += [f"The base configuration on the same left-out runs: total test MOTA "
                  f"{1 - base_errors / base_gt:.4f}"
                  f"{'' if base_gt == gt else ' (not every fold has a base trial)'}.", ""]
    if tuning.plot_correlations(out / "loocv.png", correlations):
        lines += ["![training vs test MOTA](loocv.png)", ""]
    return lines


def report_only(args, out, storage, base_yaml, space):
    """The outputs of the studies in the storage, as they stand."""
    names = study_names_in(storage, args)
    prefix = args.study + "/loo-"
    if args.loocv:
        folds = [(n[len(prefix):], None, None) for n in names if n.startswith(prefix)]
    else:
        folds = [("all", None, None)] if args.study in names else []
    if not folds:
        raise TuneError(f"--report: no {'LOOCV ' if args.loocv else ''}study '{args.study}' in "
                        f"{args.storage or out / 'study.journal'}")
    write_outputs(args, out, storage, folds, base_yaml, space)
    log(args, f"report of {len(folds)} stud{'ies' if len(folds) > 1 else 'y'}: {out}/report.md")
    return 0


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    args = parse_args(argv)
    signal.signal(signal.SIGINT, _interrupt)
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        import optuna  # noqa: F401
    except ImportError:
        print("ringtrack tune: Optuna is not installed (apt-get install python3-optuna, or "
              "scripts/bootstrap)", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        return run(args, argv)
    except TuneError as e:
        print(f"ringtrack tune: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except (rt.ConfigError, rt.InputError) as e:
        print(f"ringtrack tune: {e}", file=sys.stderr)
        return EXIT_BAD_INPUT


def run(args, argv):
    import warnings

    import optuna

    # The journal file (what Optuna recommends for several processes on one machine), heartbeats
    # and retries are marked experimental in Optuna 3.1; that is all these warnings say.
    warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)
    space = tuning.load_space(args.space)
    objectives = objectives_of(args)
    builtins = builtins_of(args)
    base_yaml = base_config_yaml(args)
    if not builtins and not args.scenario_files and not args.sequences:
        raise TuneError("no runs: --scenarios is empty and no --scenario-files or --sequences")
    out = pathlib.Path(args.out)
    storage = make_storage(args, out)  # a database is reached before anything is written
    tuning.ensure_dir(out)
    if args.worker:  # a worker writes no outputs (the main process or --report does)
        return tune_into(args, argv, out, storage, space, objectives, builtins, base_yaml)
    # run.json says whether report.md, trials.csv and the rest are whole (docs/formats.md): an
    # interrupted study wrote none of them, so it is not complete until a resumed run ends.
    status = rt.RunStatusFile(str(out / "run.json"), "tune", ["ringtrack", "tune", *argv])
    status.start()
    try:
        code = tune_into(args, argv, out, storage, space, objectives, builtins, base_yaml)
    except BaseException as e:
        status.fail(str(e) or type(e).__name__)
        raise
    if code == 0:
        status.finish()
    else:
        status.fail(f"interrupted by {signal.Signals(_stopped_by[0]).name} before the outputs "
                    "were written; run the same command again to resume the study")
    return code


def tune_into(args, argv, out, storage, space, objectives, builtins, base_yaml):
    """The tuning itself (or --report) into the output folder out."""
    if args.report:
        return report_only(args, out, storage, base_yaml, space)
    worker_index = int(os.environ.get("RINGTRACK_TUNE_WORKER_INDEX", "0"))
    children = []
    if not args.worker:
        if not args.storage:  # a local journal: RUNNING trials are left from an interrupted run
            stale = fail_trials_of(storage, study_names_in(storage, args))
            if stale:
                log(args, f"{stale} trial(s) of an interrupted session failed and queued again")
        # Workers start first: each records its own runs (in memory, once per process).
        children = start_workers(args, argv, args.workers - 1)
    start = time.monotonic()
    try:
        runs = []
        if builtins or args.scenario_files:
            runs = rt.record_runs(builtins=builtins, scenario_files=args.scenario_files,
                                  duration_s=args.duration, sensors=args.sensors, seed=args.seed)
        runs += [rt.RecordedScenario.from_sequence(folder) for folder in args.sequences]
    except BaseException:
        stop_workers(children)
        raise
    log(args, f"recorded {len(runs)} runs ({sum(len(r) for r in runs)} scans, "
        f"{sum(r.memory_bytes for r in runs) / 2**20:.0f} MiB) in {time.monotonic() - start:.1f} s")
    folds = folds_of(runs, args.loocv)
    base = None
    if not args.worker and not args.no_base_trial:
        base, outside = tuning.base_params(space, base_yaml)
        if outside:
            log(args, f"the base value of {', '.join(outside)} lies outside the search space: "
                "the first trial samples it")
    if args.worker:
        try:
            optimise(args, storage, folds, space, base_yaml, objectives, worker_index)
        except KeyboardInterrupt:
            return interrupted_status()
        return 0
    try:
        optimise(args, storage, folds, space, base_yaml, objectives, worker_index, base)
        reap(args, storage, children)
    except KeyboardInterrupt:
        stop_workers(children)
        print(f"ringtrack tune: interrupted by {signal.Signals(_stopped_by[0]).name}; run the "
              "same command again to resume the study", file=sys.stderr)
        return interrupted_status()
    write_outputs(args, out, storage, folds, base_yaml, space)
    log(args, f"done in {(time.monotonic() - start) / 60:.1f} min: {out}/report.md, "
        f"trials.csv{', loocv.png' if args.loocv else ', best.yaml'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
