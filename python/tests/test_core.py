"""Config, Pose and OrganizedScan: the same validation and messages as the C++ library."""

import math

import numpy as np
import pytest

import ringtrack as rt


def test_config_round_trips_through_yaml():
    c = rt.Config()
    c.set("tracking.confirm_hits", 3)
    c.set("segmentation.min_width_m", 0.15)
    back = rt.Config.from_yaml(c.to_yaml())
    assert back.to_yaml() == c.to_yaml()
    assert back.get_text("tracking.confirm_hits") == "3"


def test_config_rejects_unknown_keys_and_bad_values_by_name():
    c = rt.Config()
    with pytest.raises(rt.ConfigError, match="tracking.no_such_key"):
        c.set("tracking.no_such_key", 1)
    with pytest.raises(rt.ConfigError, match="segmentation.min_width_m"):
        c.set("segmentation.min_width_m", -1.0)
    with pytest.raises(rt.ConfigError, match="bogus"):
        rt.Config.from_yaml("tracking:\n  bogus: 2\n", "inline.yaml")
    with pytest.raises(rt.ConfigError):
        c.set("tracking.confirm_hits", [1, 2])
    assert isinstance(rt.ConfigError("x"), ValueError)


def test_config_dicts_nested_and_flat():
    d = rt.config_to_dict(rt.Config())
    assert set(d) >= {"segmentation", "detection", "tracking", "mapping"}
    assert d["tracking"]["confirm_hits"] == 2  # the documented default (config/default.yaml)
    c = rt.config_from_dict({"tracking": {"confirm_hits": 4}, "mapping.object_margin_m": 0.3})
    assert c.get_text("tracking.confirm_hits") == "4"
    assert float(c.get_text("mapping.object_margin_m")) == pytest.approx(0.3)
    assert rt.config_to_dict(c)["tracking"]["confirm_hits"] == 4


def test_pose_matrix_and_quaternion():
    half = math.sqrt(0.5)
    p = rt.Pose([1.0, 2.0, 3.0], [half, 0.0, 0.0, half])  # 90 degrees about z
    m = p.matrix()
    np.testing.assert_allclose(m[:3, 3], [1, 2, 3])
    np.testing.assert_allclose(m[:3, :3], [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-12)
    q = rt.Pose.from_matrix(m).quaternion_wxyz
    np.testing.assert_allclose(np.abs(q), [half, 0, 0, half], atol=1e-12)
    with pytest.raises(rt.InputError, match="finite"):
        rt.Pose([math.nan, 0, 0])
    with pytest.raises(rt.InputError, match="non-zero"):
        rt.Pose([0, 0, 0], [0, 0, 0, 0])


def test_scan_from_a_hand_made_range_image():
    model = rt.SensorModel.vlp16()
    ranges = np.full((model.rings, model.columns), np.nan, dtype=np.float32)
    ranges[0, 0] = 10.0  # bottom ring (-15 degrees), azimuth 0: the point lies in the x-z plane
    ranges[3, 5] = 0.1  # below the minimum range
    ranges[8, 9] = 500.0  # beyond the maximum range
    scan = rt.OrganizedScan.from_ranges(model, ranges, stamp_ns=1000)
    assert scan.valid_count() == 1
    assert scan.status[0, 0] == int(rt.ReturnStatus.VALID)
    assert scan.status[3, 5] == int(rt.ReturnStatus.TOO_CLOSE)
    assert scan.status[8, 9] == int(rt.ReturnStatus.TOO_FAR)
    elevation = math.radians(model.elevation_deg[0])
    assert scan.x[0, 0] == pytest.approx(10.0 * math.cos(elevation), abs=1e-3)
    assert scan.y[0, 0] == pytest.approx(0.0, abs=1e-6)
    # z adds the ring's vertical beam offset (a few millimetres on the VLP-16).
    assert scan.z[0, 0] == pytest.approx(10.0 * math.sin(elevation), abs=0.02)
    assert scan.points().shape == (1, 3)
    assert scan.column_stamp_ns[0] == 1000
    with pytest.raises(rt.InputError, match="expected shape"):
        rt.OrganizedScan.from_ranges(model, np.zeros((4, 4), dtype=np.float32))


def test_scan_arrays_are_read_only_views():
    model = rt.SensorModel.vlp16()
    scan = rt.OrganizedScan.from_ranges(model, np.full((16, model.columns), 5.0, np.float32))
    r = scan.ranges
    assert r.shape == (16, model.columns) and r.dtype == np.float32
    assert not r.flags.writeable and not r.flags.owndata  # a view of the scan's memory
    with pytest.raises(ValueError):
        r[0, 0] = 1.0
    del scan  # the view keeps the scan alive
    assert float(r[2, 2]) == 5.0
