"""ringtrack: detect and track people in spinning-LiDAR scans and build static maps.

Bindings over the C++ library (docs/python.md): Config, Pipeline, the sources (recordings,
sequence folders, live UDP), a whole run (`run`), the simulator, evaluation, the benchmark engine
and the MCAP writer for Foxglove. The tuner is
`python3 -m ringtrack.tune` (also `ringtrack tune`).
"""

import os as _os
import pathlib as _pathlib

from . import _ringtrack
from ._ringtrack import (  # noqa: F401  (re-exported)
    Config,
    ConfigError,
    Detection,
    Frame,
    InputError,
    McapWriter,
    OrganizedScan,
    Pipeline,
    Pose,
    RecordedScenario,
    ReturnStatus,
    ScanSource,
    SensorModel,
    Sequence,
    Simulator,
    Track,
    __version__,
    evaluate,
    map_rates,
    open,
    record_runs,
    run,
    run_case,
    run_cases,
    scenario_files_in,
    scenarios,
)


def _config_dir():
    """The shipped config/: the source tree's for the build tree's package, else the one
    `cmake --install` put in <prefix>/share/ringtrack/ (an installed package never reads a
    source tree)."""
    here = _pathlib.Path(__file__).resolve().parent
    if here == _pathlib.Path(_ringtrack._build_package_dir).resolve():
        return _ringtrack._source_config_dir
    return _os.path.normpath(here / _ringtrack._installed_config_dir)


config_dir = _config_dir()
"""Where the default search space (tune_space.yaml) and the validation scenarios are."""


def config_to_dict(config):
    """The configuration as nested dicts {section: {key: value}} (values typed by YAML)."""
    import yaml

    return yaml.safe_load(config.to_yaml())


def config_from_dict(values, base=None):
    """A Config with values applied: nested {section: {key: v}} or flat {"section.key": v}."""
    config = Config() if base is None else base
    for key, value in _flatten(values):
        config.set(key, value)
    config.validate()
    return config


def _flatten(values, prefix=""):
    for key, value in values.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            yield from _flatten(value, name + ".")
        else:
            yield name, value
