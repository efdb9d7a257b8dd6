"""The parts of `ringtrack tune` that do not depend on Optuna's storage: the search space file,
the trial objective (the pipeline run in-process on recorded scenarios), pooled metrics, the
Pearson correlation and the reports. See docs/tuning.md."""

import csv
import math
import os
import pathlib
import time

import yaml

from . import _ringtrack as rt

KINDS = ("float", "int", "choice")


class TuneError(Exception):
    """A problem with the tuner's input: one line naming the file, key or value."""


class Parameter:
    """One dimension of the search space."""

    def __init__(self, key, kind, low=None, high=None, log=False, choices=None):
        self.key, self.kind, self.low, self.high, self.log = key, kind, low, high, log
        self.choices = choices

    def suggest(self, trial):
        if self.kind == "float":
            return trial.suggest_float(self.key, self.low, self.high, log=self.log)
        if self.kind == "int":
            return trial.suggest_int(self.key, self.low, self.high, log=self.log)
        return trial.suggest_categorical(self.key, self.choices)

    def __repr__(self):
        if self.kind == "choice":
            return f"{self.key} in {self.choices}"
        return f"{self.key} in [{self.low}, {self.high}]{' (log)' if self.log else ''}"


def load_space(path):
    """Reads a search space file; raises TuneError naming the file and key on any problem:
    an unknown configuration key, an empty or reversed range, a value outside the key's own
    allowed range, an unknown type or field."""
    path = str(path)
    try:
        with open(path, encoding="utf-8") as f:
            doc = yaml.safe_load(f)
    except OSError as e:
        raise TuneError(f"{path}: cannot read the search space: {e.strerror}") from None
    except yaml.YAMLError as e:
        raise TuneError(f"{path}: not valid YAML: {str(e).splitlines()[0]}") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("parameters"), dict):
        raise TuneError(f"{path}: expected a mapping 'parameters: {{key: {{type, low, high}}}}'")
    unknown = set(doc) - {"parameters"}
    if unknown:
        raise TuneError(f"{path}: unknown top-level key '{sorted(unknown)[0]}' (expected parameters)")
    if not doc["parameters"]:
        raise TuneError(f"{path}: 'parameters' is empty: nothing to tune")
    known_keys = set(rt.Config().keys())
    return [_parse_parameter(path, key, spec, known_keys) for key, spec in doc["parameters"].items()]


def _parse_parameter(path, key, spec, known_keys):
    where = f"{path}: parameters.{key}"
    if key not in known_keys:
        raise TuneError(f"{where}: unknown configuration key (see `ringtrack dump-config`)")
    if not isinstance(spec, dict):
        raise TuneError(f"{where}: expected a mapping with type, low, high (or choices)")
    allowed = {"type", "low", "high", "log", "choices"}
    extra = set(spec) - allowed
    if extra:
        raise TuneError(f"{where}: unknown field '{sorted(extra)[0]}' (expected {', '.join(sorted(allowed))})")
    kind = spec.get("type", "float")
    if kind not in KINDS:
        raise TuneError(f"{where}: type '{kind}' is not one of {', '.join(KINDS)}")
    if kind == "choice":
        choices = spec.get("choices")
        if not isinstance(choices, list) or not choices:
            raise TuneError(f"{where}: a choice needs a non-empty list 'choices'")
        for c in choices:
            _check_value(where, key, c)
        return Parameter(key, kind, choices=choices)
    low, high, log = spec.get("low"), spec.get("high"), bool(spec.get("log", False))
    number = int if kind == "int" else (int, float)
    if not isinstance(low, number) or not isinstance(high, number) or isinstance(low, bool):
        raise TuneError(f"{where}: low and high must be {'integers' if kind == 'int' else 'numbers'}")
    if not (math.isfinite(low) and math.isfinite(high)) or not low < high:
        raise TuneError(f"{where}: empty range [{low}, {high}] (need low < high)")
    if log and low <= 0:
        raise TuneError(f"{where}: a log range needs low > 0")
    _check_value(where, key, low)
    _check_value(where, key, high)
    return Parameter(key, kind, float(low) if kind == "float" else low,
                     float(high) if kind == "float" else high, log)


def _check_value(where, key, value):
    try:
        rt.Config().set(key, value)
    except rt.ConfigError as e:
        raise TuneError(f"{where}: {value!r} is outside the key's allowed values ({e})") from None


def base_params(space, base_yaml):
    """The base configuration's value of every key of the space whose value lies inside the
    key's range (or among its choices): enqueued as the first trial of each study, so that the
    best trial is never worse on the training runs than the configuration the study started from.
    Returns (params, keys outside the space); the sampler draws the keys outside."""
    config = rt.Config.from_yaml(base_yaml, "base configuration")
    params, outside = {}, []
    for p in space:
        value = yaml.safe_load(config.get_text(p.key))
        if p.kind == "choice":
            inside = value in p.choices
        else:
            number = isinstance(value, (int, float)) and not isinstance(value, bool)
            inside = number and p.low <= value <= p.high
            if inside and p.kind == "int":
                inside = float(value).is_integer()
            if inside:
                value = int(value) if p.kind == "int" else float(value)
        if inside:
            params[p.key] = value
        else:
            outside.append(p.key)
    return params, outside


def config_for(params, base_yaml):
    """The base configuration with a trial's parameters applied (ConfigError when invalid)."""
    config = rt.Config.from_yaml(base_yaml, "base configuration")
    for key, value in params.items():
        config.set(key, value)
    config.validate()
    return config


def pooled(cases):
    """MOTA, IDF1 and mean ms per scan of several cases from their summed counts (the
    benchmark's group figures: sums, never averages)."""
    keys = ("misses", "false_positives", "id_switches", "gt_presences", "id_true_positives",
            "id_false_positives", "id_false_negatives")
    total = {k: sum(c["metrics"][k] for c in cases) for k in keys}
    gt = total["gt_presences"]
    errors = total["misses"] + total["false_positives"] + total["id_switches"]
    mota = 1.0 - errors / gt if gt > 0 else float("nan")
    idtp = total["id_true_positives"]
    denominator = 2 * idtp + total["id_false_positives"] + total["id_false_negatives"]
    idf1 = 2 * idtp / denominator if denominator > 0 else float("nan")
    scans = sum(c["scans"] for c in cases)
    ms = 1000.0 * sum(c["pipeline_s"] for c in cases) / scans if scans else float("nan")
    return {"mota": mota, "idf1": idf1, "ms_per_scan": ms, "errors": errors, "gt_presences": gt}


def pearson(xs, ys):
    """Pearson correlation coefficient r (the paper's Fig. 5); nan for fewer than two pairs or
    no spread."""
    pairs = [(x, y) for x, y in zip(xs, ys) if math.isfinite(x) and math.isfinite(y)]
    n = len(pairs)
    if n < 2:
        return float("nan")
    mx = sum(x for x, _ in pairs) / n
    my = sum(y for _, y in pairs) / n
    sxy = sum((x - mx) * (y - my) for x, y in pairs)
    sxx = sum((x - mx) ** 2 for x, _ in pairs)
    syy = sum((y - my) ** 2 for _, y in pairs)
    if sxx == 0 or syy == 0:
        return float("nan")
    return sxy / math.sqrt(sxx * syy)


OBJECTIVES = {
    # name: (direction, how to read it from pooled figures)
    "mota": ("minimize", lambda p: 1.0 - p["mota"]),
    "idf1": ("minimize", lambda p: 1.0 - p["idf1"]),
    "ms": ("minimize", lambda p: p["ms_per_scan"]),
}


class Objective:
    """One trial: the configuration from the sampled parameters, a fresh pipeline over every
    training run (recorded once per process), optionally the left-out test run, and the costs.
    Invalid combinations (e.g. min > max) are pruned, never scored."""

    def __init__(self, space, train, test, base_yaml, objectives, worker):
        self.space, self.train, self.test = space, train, test
        self.base_yaml, self.objectives, self.worker = base_yaml, objectives, worker

    def __call__(self, trial):
        import optuna

        trial.set_user_attr("worker", self.worker)
        params = {p.key: p.suggest(trial) for p in self.space}
        try:
            config = config_for(params, self.base_yaml)
        except rt.ConfigError as e:
            trial.set_user_attr("invalid", str(e))
            raise optuna.TrialPruned(f"invalid configuration: {e}") from None
        start = time.monotonic()
        train = pooled(rt.run_cases(self.train, config)["cases"])
        trial.set_user_attr("train_mota", train["mota"])
        trial.set_user_attr("train_idf1", train["idf1"])
        trial.set_user_attr("ms_per_scan", train["ms_per_scan"])
        if self.test is not None:
            test = pooled([rt.run_case(self.test, config)])
            trial.set_user_attr("test_mota", test["mota"])
            trial.set_user_attr("test_errors", test["errors"])
            trial.set_user_attr("test_gt", test["gt_presences"])
        trial.set_user_attr("seconds", time.monotonic() - start)
        costs = [OBJECTIVES[name][1](train) for name in self.objectives]
        return costs[0] if len(costs) == 1 else costs


def best_trial(study):
    """The trial with the lowest first cost (for several objectives: the Pareto front's best
    MOTA)."""
    import optuna

    done = [t for t in study.trials if t.state == optuna.trial.TrialState.COMPLETE]
    if not done:
        return None
    return min(done, key=lambda t: t.values[0])


def base_trial(study):
    """The completed trial that ran the base configuration (`base_params`), or None."""
    import optuna

    done = [t for t in study.trials
            if t.user_attrs.get("base") and t.state == optuna.trial.TrialState.COMPLETE]
    return done[0] if done else None


def write_trials_csv(path, studies):
    """Every trial of every study: fold, number, state, costs, MOTAs, seconds, whether it ran the
    base configuration, parameters."""
    import optuna

    keys = sorted({k for s in studies.values() for t in s.trials for k in t.params})
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(["fold", "trial", "state", "cost", "train_mota", "test_mota", "train_idf1",
                     "ms_per_scan", "seconds", "worker", "base", *keys])
        for fold, study in studies.items():
            for t in study.trials:
                a = t.user_attrs
                cost = t.values[0] if t.state == optuna.trial.TrialState.COMPLETE else ""
                w.writerow([fold, t.number, t.state.name, cost, a.get("train_mota", ""),
                            a.get("test_mota", ""), a.get("train_idf1", ""),
                            a.get("ms_per_scan", ""), a.get("seconds", ""), a.get("worker", ""),
                            1 if a.get("base") else 0, *[t.params.get(k, "") for k in keys]])


def fold_correlation(study):
    """(train MOTAs, test MOTAs, r) over the completed trials of a LOOCV fold."""
    import optuna

    done = [t for t in study.trials if t.state == optuna.trial.TrialState.COMPLETE
            and "test_mota" in t.user_attrs]
    xs = [t.user_attrs["train_mota"] for t in done]
    ys = [t.user_attrs["test_mota"] for t in done]
    return xs, ys, pearson(xs, ys)


def plot_correlations(path, folds):
    """Fig. 5-style scatter plots: per fold, training MOTA against test MOTA over the trials,
    titled with the left-out run and r. Returns False (and says why) without matplotlib."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("ringtrack tune: warning: no plot: python3-matplotlib is not installed", file=os.sys.stderr)
        return False
    n = len(folds)
    cols = min(4, n)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 3.0 * rows), squeeze=False)
    for ax in axes.flat[n:]:
        ax.axis("off")
    for ax, (stem, (xs, ys, r)) in zip(axes.flat, folds.items()):
        ax.scatter(xs, ys, s=8, alpha=0.6)
        ax.set_title(f"test {stem}, r = {r:.2f}" if math.isfinite(r) else f"test {stem}, r = -",
                     fontsize=9)
        ax.set_xlabel("MOTA training set", fontsize=8)
        ax.set_ylabel("MOTA test sequence", fontsize=8)
        ax.tick_params(labelsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


def ensure_dir(path):
    p = pathlib.Path(path)
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise TuneError(f"{p}: cannot create the output folder: {e.strerror}") from None
    return p
