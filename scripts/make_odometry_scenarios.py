#!/usr/bin/python3
"""Writes the moving-sensor scenarios of config/odometry/ (docs/odometry.md, "Accuracy").

Deterministic: running it again gives the same files.
    /usr/bin/python3 scripts/make_odometry_scenarios.py [OUT_DIR [NAME ...]]
(default config/odometry, every scenario; python3-numpy and python3-yaml)

Each file is a built-in world (config/scenarios/) with a scripted sensor (keyframes every 0.1 s
or finer) that looks like real use, 100 s long:
  town-drive       a vehicle roof sensor (2 m) driving back and forth along the longest straight
                   street of the town that keeps 4 m from every solid: from rest to 10 m/s and
                   back to rest at 3 m/s^2, turning on the spot (4 s) at each end
  industrial-walk  a handheld sensor (1.4 m) carried at 1.4 m/s around the longest rounded
                   rectangle of the industrial site that keeps 1.5 m from every solid, bobbing
                   3 cm, pitching +-4 deg with the steps and +-8 deg slowly, rolling +-2 deg, and
                   yawing +-25 deg as the operator looks around
  park-climb       a MAV circling (6 m radius, 3 m/s) among the park's trees while climbing 10 m
                   (2.5 to 12.5 m), banked into the turn
Routes are searched on a clearance grid (conservative 2-D footprints); the simulator checks the
sensor path against every solid again when the file is loaded.
"""

import math
import os
import sys

import numpy as np
import yaml

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
DURATION_S = 100.0


def load(name):
    with open(os.path.join(ROOT, "config", "scenarios", name)) as f:
        return yaml.safe_load(f)


def clearance_grid(world, half_m, cell_m=0.5, top_m=1e9):
    """Horizontal distance to the nearest solid on a grid of cell_m over [-half_m, half_m]^2
    (conservative 2-D footprints: boxes, cylinders, ellipsoids reaching below top_m at full
    radius, walls)."""
    axis = np.arange(-half_m, half_m + cell_m / 2, cell_m)
    x, y = np.meshgrid(axis, axis, indexing="ij")
    best = np.full(x.shape, 1e9)
    for b in world.get("boxes") or []:
        cx, cy = b["center_m"]
        yaw = math.radians(b.get("yaw_deg", 0.0))
        dx, dy = x - cx, y - cy
        u = math.cos(yaw) * dx + math.sin(yaw) * dy
        v = -math.sin(yaw) * dx + math.cos(yaw) * dy
        ex = np.maximum(np.abs(u) - b["size_m"][0] / 2, 0.0)
        ey = np.maximum(np.abs(v) - b["size_m"][1] / 2, 0.0)
        best = np.minimum(best, np.hypot(ex, ey))
    for c in world.get("cylinders") or []:
        cx, cy = c["center_m"]
        best = np.minimum(best, np.hypot(x - cx, y - cy) - c["radius_m"])
    for e in world.get("ellipsoids") or []:
        cx, cy, cz = e["center_m"]
        if cz - e["radii_m"][2] > top_m:  # a crown above the sensor's path
            continue
        best = np.minimum(best, np.hypot(x - cx, y - cy) - max(e["radii_m"][0], e["radii_m"][1]))
    for w in world.get("walls") or []:
        (ax, ay), (bx, by) = w["from_m"], w["to_m"]
        lx, ly = bx - ax, by - ay
        t = np.clip(((x - ax) * lx + (y - ay) * ly) / max(lx * lx + ly * ly, 1e-9), 0.0, 1.0)
        best = np.minimum(best, np.hypot(x - ax - t * lx, y - ay - t * ly) - w.get("thickness_m", 0.2))
    return {"values": best, "half": half_m, "cell": cell_m}


def clear_at(grid, xs, ys):
    i = np.clip(np.round((np.asarray(xs) + grid["half"]) / grid["cell"]).astype(int), 0,
                grid["values"].shape[0] - 1)
    j = np.clip(np.round((np.asarray(ys) + grid["half"]) / grid["cell"]).astype(int), 0,
                grid["values"].shape[1] - 1)
    return grid["values"][i, j]


def rounded_rectangle(cx, cy, a, b, r):
    """Pose function s -> (x, y, heading) of a counter-clockwise rounded rectangle and its length."""
    legs = [(2 * a - 2 * r), (2 * b - 2 * r), (2 * a - 2 * r), (2 * b - 2 * r)]
    arc = 0.5 * math.pi * r
    length = sum(legs) + 4 * arc
    start = (cx - a + r, cy - b)

    def at(s):
        s = s % length
        x, y = start
        heading = 0.0
        for leg in legs:
            if s <= leg:
                return x + s * math.cos(heading), y + s * math.sin(heading), heading
            x += leg * math.cos(heading)
            y += leg * math.sin(heading)
            s -= leg
            # Left turn of radius r about the centre to the left of the heading.
            ox, oy = x - r * math.sin(heading), y + r * math.cos(heading)
            phi = min(s, arc) / r
            if s <= arc:
                return (ox + r * math.sin(heading + phi), oy - r * math.cos(heading + phi),
                        heading + phi)
            x, y = ox + r * math.sin(heading + 0.5 * math.pi), oy - r * math.cos(heading + 0.5 * math.pi)
            heading += 0.5 * math.pi
            s -= arc
        return x, y, heading

    return at, length


def best_rectangle(grid, sizes, centres, radius, min_clear, max_reach, step):
    """The longest rounded rectangle (a, b half sizes about cx, cy) whose path keeps min_clear."""
    best = None
    for a in sizes:
        for b in sizes:
            for cx in centres:
                for cy in centres:
                    if math.hypot(abs(cx) + a, abs(cy) + b) > max_reach:
                        continue
                    at, length = rounded_rectangle(cx, cy, a, b, radius)
                    if best is not None and length <= best[0]:
                        continue
                    pts = [at(s) for s in np.arange(0.0, length, step)]
                    xs = [p[0] for p in pts]
                    ys = [p[1] for p in pts]
                    if clear_at(grid, xs, ys).min() >= min_clear:
                        best = (length, cx, cy, a, b)
    if best is None:
        sys.exit("no clear route found")
    return best


def scenario_with(world, name, description, keyframes):
    s = dict(world)
    s["name"] = name
    s["description"] = description
    s["duration_s"] = DURATION_S
    sensor = dict(world["sensor"])
    sensor["motion"] = "scripted"
    sensor["keyframes"] = keyframes
    s["sensor"] = sensor
    return s


def kf(t, x, y, z, roll, pitch, yaw):
    return [round(float(v), 3) for v in (t, x, y, z, roll, pitch, yaw)]


def unwrap_deg(heading_rad, previous_deg):
    d = math.degrees(heading_rad)
    if previous_deg is None:
        return d
    while d - previous_deg > 180:
        d -= 360
    while d - previous_deg < -180:
        d += 360
    return d


def longest_clear_line(grid, min_clear, reach):
    """The longest straight segment within reach of the centre that keeps min_clear."""
    best = (0.0, None)
    ts = np.arange(-reach, reach, 1.0)
    for deg in range(0, 180, 2):
        ux, uy = math.cos(math.radians(deg)), math.sin(math.radians(deg))
        for d in np.arange(-80.0, 81.0, 2.0):
            xs, ys = -uy * d + ux * ts, ux * d + uy * ts
            ok = (clear_at(grid, xs, ys) >= min_clear) & (np.hypot(xs, ys) <= reach)
            run, start = 0, 0
            for i, flag in enumerate(list(ok) + [False]):
                if flag:
                    run += 1
                    continue
                if run - 1 > best[0]:
                    a, b = start, start + run - 1
                    best = (float(run - 1), ((xs[a], ys[a]), (xs[b], ys[b])))
                run, start = 0, i + 1
    return best


def trapezoid_distance(t, length, cruise, accel):
    """Distance after t s along a leg of `length` from rest to rest (accelerate, cruise, brake)."""
    t_acc = cruise / accel
    d_acc = 0.5 * accel * t_acc * t_acc
    if 2 * d_acc > length:  # never reaches cruise speed
        t_acc = math.sqrt(length / accel)
        d_acc, cruise = 0.5 * length, accel * t_acc
    t_cruise = (length - 2 * d_acc) / cruise
    if t < t_acc:
        return 0.5 * accel * t * t
    if t < t_acc + t_cruise:
        return d_acc + cruise * (t - t_acc)
    tb = min(t - t_acc - t_cruise, t_acc)
    return d_acc + cruise * t_cruise + cruise * tb - 0.5 * accel * tb * tb


def leg_time(length, cruise, accel):
    """Duration of such a leg."""
    t_acc = cruise / accel
    if accel * t_acc * t_acc > length:
        return 2 * math.sqrt(length / accel)
    return 2 * t_acc + (length - accel * t_acc * t_acc) / cruise


def town_drive():
    world = load("5-town.yaml")
    grid = clearance_grid(world, 140.0, top_m=3.0)
    length, (a, b) = longest_clear_line(grid, 4.0, 125.0)
    # The street ends where something stands: stop 10 m before.
    ux, uy = (b[0] - a[0]) / length, (b[1] - a[1]) / length
    a, b = (a[0] + 10 * ux, a[1] + 10 * uy), (b[0] - 10 * ux, b[1] - 10 * uy)
    length -= 20
    heading = math.degrees(math.atan2(uy, ux))
    cruise, accel, spin_s = 10.0, 3.0, 4.0
    t_leg = leg_time(length, cruise, accel)
    frames = []
    for k in range(int(DURATION_S / 0.1) + 1):
        t = 0.1 * k
        cycle, leg = divmod(t, t_leg + spin_s)
        forward = int(cycle) % 2 == 0
        start, direction = (a, 1.0) if forward else (b, -1.0)
        yaw = heading + 180.0 * (int(cycle) % 2) + 360.0 * (int(cycle) // 2)
        if leg <= t_leg:
            d = trapezoid_distance(leg, length, cruise, accel)
            x, y = start[0] + direction * d * ux, start[1] + direction * d * uy
        else:  # turning on the spot at the end of the street (a skid-steer vehicle)
            x, y = (b if forward else a)
            u = (leg - t_leg) / spin_s
            yaw += 180.0 * (3 * u * u - 2 * u * u * u)
        frames.append(kf(t, x, y, 2.0, 0.0, 0.0, yaw))
    desc = ("town, a vehicle roof sensor (2 m) driving the longest clear straight street (%.0f m "
            "from (%.0f, %.0f) to (%.0f, %.0f)) back and forth: from rest to 10 m/s and back to "
            "rest at 3 m/s^2, turning on the spot in 4 s at each end, 100 s"
            % (length, a[0], a[1], b[0], b[1]))
    return scenario_with(world, "town-drive", desc, frames)


def industrial_walk():
    world = load("4-industrial.yaml")
    grid = clearance_grid(world, 60.0, 0.25)
    length, cx, cy, a, b = best_rectangle(grid, range(6, 31, 1), range(-20, 21, 2), 3.0, 1.5,
                                          45.0, 0.5)
    at, _ = rounded_rectangle(cx, cy, a, b, 3.0)
    frames, yaw = [], None
    for k in range(int(DURATION_S / 0.05) + 1):
        t = 0.05 * k
        x, y, h = at(1.4 * t)
        yaw = unwrap_deg(h, yaw)
        look = 25.0 * math.sin(2 * math.pi * 0.13 * t)
        pitch = 4.0 * math.sin(2 * math.pi * 1.0 * t) + 8.0 * math.sin(2 * math.pi * 0.07 * t)
        roll = 2.0 * math.sin(2 * math.pi * 0.9 * t + 1.0)
        z = 1.4 + 0.03 * math.sin(2 * math.pi * 2.0 * t)
        frames.append(kf(t, x, y, z, roll, pitch, yaw + look))
    desc = ("industrial site, a handheld sensor carried at 1.4 m/s around a %.0f m loop, pitching, "
            "rolling and looking around, 100 s" % length)
    return scenario_with(world, "industrial-walk", desc, frames)


def park_climb():
    world = load("6-park.yaml")
    radius, speed = 6.0, 3.0
    grid = clearance_grid(world, 80.0)
    phis = np.linspace(0.0, 2 * math.pi, 90, endpoint=False)
    best = None
    for cx in range(-40, 41, 1):
        for cy in range(-60, 61, 1):
            clear = clear_at(grid, cx + radius * np.cos(phis), cy + radius * np.sin(phis)).min()
            score = clear - 0.01 * math.hypot(cx, cy)
            if clear >= 1.5 and (best is None or score > best[0]):
                best = (score, cx, cy)
    if best is None:
        sys.exit("no clear circle in the park")
    _, cx, cy = best
    omega = speed / radius
    bank = math.degrees(math.atan(speed * speed / radius / 9.81))
    frames = []
    for k in range(int(DURATION_S / 0.1) + 1):
        t = 0.1 * k
        # Speeds up from a hover over the first 3 s (a multirotor does not start at 3 m/s).
        ramp = min(1.0, t / 3.0)
        phi = omega * (t - 1.5 if t >= 3.0 else 0.5 * t * t / 3.0)
        x, y = cx + radius * math.cos(phi), cy + radius * math.sin(phi)
        z = 2.5 + 10.0 * t / DURATION_S
        heading = math.degrees(phi) + 90.0
        frames.append(kf(t, x, y, z, -bank * ramp, 2.0 * ramp, heading))
    desc = ("park, a MAV circling (%.0f m radius, 3 m/s) about (%d, %d) while climbing from 2.5 to "
            "12.5 m, banked into the turn, 100 s" % (radius, cx, cy))
    return scenario_with(world, "park-climb", desc, frames)


class FlowList(list):
    pass


def flow_list_representer(dumper, data):
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=True)


def write(out_dir, scenario):
    yaml.add_representer(FlowList, flow_list_representer)

    def flow(v):
        if isinstance(v, list):
            return FlowList([flow(x) for x in v]) if all(not isinstance(x, (dict,)) for x in v) else [flow(x) for x in v]
        if isinstance(v, dict):
            return {k: flow(x) for k, x in v.items()}
        return v

    s = {k: flow(v) for k, v in scenario.items()}
    s["sensor"]["keyframes"] = [FlowList(f) for f in scenario["sensor"]["keyframes"]]
    path = os.path.join(out_dir, scenario["name"] + ".yaml")
    with open(path, "w") as f:
        f.write("# ringtrack simulator scenario (docs/formats.md), written by "
                "scripts/make_odometry_scenarios.py: do not edit by hand\n")
        yaml.dump(s, f, sort_keys=False, default_flow_style=False, width=100)
    print(path, scenario["description"])


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "config", "odometry")
    os.makedirs(out_dir, exist_ok=True)
    makers = {"town-drive": town_drive, "industrial-walk": industrial_walk, "park-climb": park_climb}
    only = sys.argv[2:]
    for name, make in makers.items():
        if only and name not in only:
            continue
        write(out_dir, make())


if __name__ == "__main__":
    main()
