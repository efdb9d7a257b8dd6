#!/usr/bin/python3
"""Writes the validation scenarios of config/validation/ (scenario YAML + trajectory CSV).

Deterministic (fixed seeds, standard library only): running it again gives the same files.
    /usr/bin/python3 scripts/make_validation_scenarios.py [OUT_DIR]    (default config/validation)

These scenarios exist to check that accuracy changes generalise: never tune on them
(docs/simulator.md, "Validation scenarios").

Walking model: a route is a polyline of hand-placed control points; its corners are rounded with
circular arcs (smooth turns), and a walker moves along the rounded path at 0.8-1.6 m/s (a slow
+-5 % sway of speed, accelerating from and braking to a stand). Groups walk side by side at 0.5-0.8
m lateral spacing around a virtual centre that follows a route (formation kept through turns), and
split into individual routes later. People stand (chat, wait) for given periods. Every person is
checked against obstacles (segments, grown by a body margin), the sensor's mast and its figure-8
flight area, and against every other person (no two closer than 0.6 m unless in one group).
Waypoints are written every 0.5 s; each person exists from its first to its last row.
"""

import math
import os
import random
import sys

SAMPLE_S = 0.5  # waypoint spacing written to the CSV
FINE_S = 0.1  # internal time step for formation and conflict checks
BODY_MARGIN_M = 0.45  # obstacle clearance of path centre lines (the simulator demands 0.2)
MIN_GAP_M = 0.6  # between people of different groups
MAX_SPEED_MPS = 1.6  # walkers: 0.8-1.6 m/s
FLIGHT_BOX = (4.7, 2.7)  # half sizes of the figure-8 area about the sensor, kept free of people


# ---- geometry ----------------------------------------------------------------------------------


def seg_point_dist(a, b, p):
    ax, ay = a
    bx, by = b
    dx, dy = bx - ax, by - ay
    l2 = dx * dx + dy * dy
    t = 0.0 if l2 == 0 else max(0.0, min(1.0, ((p[0] - ax) * dx + (p[1] - ay) * dy) / l2))
    return math.hypot(ax + t * dx - p[0], ay + t * dy - p[1])


def seg_hits_rect(a, b, center, half, yaw_rad, margin):
    """Liang-Barsky: does segment a-b pass within margin of the yawed rectangle?"""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    rx, ry = a[0] - center[0], a[1] - center[1]
    o = (c * rx + s * ry, -s * rx + c * ry)
    dx, dy = b[0] - a[0], b[1] - a[1]
    d = (c * dx + s * dy, -s * dx + c * dy)
    t0, t1 = 0.0, 1.0
    for k in range(2):
        h = half[k] + margin
        if abs(d[k]) < 1e-12:
            if abs(o[k]) > h:
                return False
            continue
        ta, tb = (-h - o[k]) / d[k], (h - o[k]) / d[k]
        if ta > tb:
            ta, tb = tb, ta
        t0, t1 = max(t0, ta), min(t1, tb)
        if t0 > t1:
            return False
    return True


# ---- scene -------------------------------------------------------------------------------------


class Scene:
    def __init__(self, name, description, duration_s, seed, sensor_xy=(0.0, 0.0)):
        self.name = name
        self.description = description
        self.duration_s = duration_s
        self.rng = random.Random(seed)
        self.sensor_xy = sensor_xy
        self.boxes = []  # (cx, cy, sx, sy, sz, yaw_deg, refl, label)
        self.cylinders = []  # (cx, cy, r, h, refl, label)
        self.ellipsoids = []  # (cx, cy, cz, rx, ry, rz, refl)
        self.walls = []  # (x0, y0, x1, y1, h, thickness, refl)
        self.people = []  # dicts: id, height, width, refl, samples [(t, x, y)], group
        self.next_id = 1

    # -- world
    def box(self, cx, cy, sx, sy, sz, yaw_deg=0.0, refl=0.5, label="box"):
        self.boxes.append((cx, cy, sx, sy, sz, yaw_deg, refl, label))

    def car(self, cx, cy, along_y=True, van=False):
        r = self.rng
        length, width, height = (5.4, 2.05, 2.3) if van else (4.5, 1.8, r.uniform(1.4, 1.55))
        sx, sy = (width, length) if along_y else (length, width)
        self.box(cx, cy, sx, sy, round(height, 2), 0.0, round(r.uniform(0.3, 0.75), 2),
                 "van" if van else "car")

    def post(self, cx, cy, radius=0.1, height=1.0, refl=0.6):
        self.cylinders.append((cx, cy, radius, height, refl, "post"))

    def tree(self, cx, cy):
        r = self.rng
        trunk = r.uniform(2.2, 3.2)
        crown = r.uniform(1.4, 2.6)
        self.cylinders.append((cx, cy, round(r.uniform(0.12, 0.25), 2), round(trunk + 0.5, 2),
                               0.35, "trunk"))
        self.ellipsoids.append((cx, cy, round(trunk + 0.8 * crown, 2), round(crown, 2),
                                round(crown * 0.9, 2), round(crown * 0.8, 2), 0.3))

    def segment_blocked(self, a, b, margin=BODY_MARGIN_M):
        """Name of what the segment a-b passes within margin of, or None."""
        for cx, cy, sx, sy, _sz, yaw, _refl, label in self.boxes:
            if seg_hits_rect(a, b, (cx, cy), (sx / 2, sy / 2), math.radians(yaw), margin):
                return "%s at (%g, %g)" % (label, cx, cy)
        for x0, y0, x1, y1, _h, th, _refl in self.walls:
            c = ((x0 + x1) / 2, (y0 + y1) / 2)
            half = (math.hypot(x1 - x0, y1 - y0) / 2, th / 2)
            if seg_hits_rect(a, b, c, half, math.atan2(y1 - y0, x1 - x0), margin):
                return "wall"
        for cx, cy, rad, _h, _refl, label in self.cylinders:
            if seg_point_dist(a, b, (cx, cy)) <= rad + margin:
                return "%s at (%g, %g)" % (label, cx, cy)
        for cx, cy, cz, rx, ry, rz, _refl in self.ellipsoids:
            if cz - rz < 1.95 and seg_point_dist(a, b, (cx, cy)) <= max(rx, ry) + margin:
                return "bush at (%g, %g)" % (cx, cy)
        if seg_hits_rect(a, b, self.sensor_xy, FLIGHT_BOX, 0.0, 0.3):
            return "the sensor's flight area"
        return None

    # -- people
    def new_person(self, group=None, height=None):
        r = self.rng
        h = height if height is not None else r.uniform(1.5, 1.95)
        # Width grows mildly with height, with its own spread.
        w = min(0.78, max(0.42, r.uniform(0.85, 1.15) * (0.32 + 0.16 * h)))
        return {"id": None, "height": round(h, 2), "width": round(w, 2),
                "refl": round(r.uniform(0.15, 0.6), 2), "samples": [], "group": group}

    def add(self, person, samples):
        """Checks and adds a person with its fine samples [(t, x, y)]; False on a conflict."""
        for (t0, x0, y0), (t1, x1, y1) in zip(samples, samples[1:]):
            what = self.segment_blocked((x0, y0), (x1, y1))
            if what:
                raise SystemExit("%s: person starting at t=%.1f s (%.1f, %.1f): at t=%.1f s the "
                                 "path is blocked by %s" % (self.name, samples[0][0],
                                                            samples[0][1], samples[0][2], t0, what))
        if samples[0][0] < -1e-9 or samples[-1][0] > self.duration_s + 1e-9:
            raise SystemExit("%s: person starting at t=%.1f s outside the scenario's time"
                             % (self.name, samples[0][0]))
        if self.conflicts(person, samples):
            return False
        person["samples"] = samples
        person["id"] = self.next_id  # ids in the order people are accepted
        self.next_id += 1
        self.people.append(person)
        return True

    def conflicts(self, person, samples):
        index = {round(t / FINE_S): (x, y) for t, x, y in samples}
        for other in self.people:
            if person["group"] is not None and other["group"] == person["group"]:
                continue
            for t, x, y in other["samples"]:
                q = index.get(round(t / FINE_S))
                if q and math.hypot(q[0] - x, q[1] - y) < MIN_GAP_M:
                    return True
        return False

    def try_add(self, make, attempts=40):
        """Calls make(attempt) -> (person, samples) until one fits; raises when none does."""
        for k in range(attempts):
            person, samples = make(k)
            if self.add(person, samples):
                return person
        raise SystemExit("%s: no conflict-free variant after %d attempts" % (self.name, attempts))

    # -- output
    def write(self, out_dir):
        csv_name = self.name + ".csv"
        with open(os.path.join(out_dir, self.name + ".yaml"), "w") as f:
            f.write("# ringtrack VALIDATION scenario, generated by scripts/make_validation_scenarios.py\n")
            f.write("# (do not edit by hand). Never tune on it: docs/simulator.md, \"Validation scenarios\".\n")
            f.write("name: %s\n" % self.name)
            f.write("description: \"%s\"\n" % self.description)
            f.write("duration_s: %g\n" % self.duration_s)
            f.write("area_m: [100, 100]\n")
            f.write("sensor: {position_m: [%g, %g, 2.5]}\n" % self.sensor_xy)
            f.write("actors: {people: 0, trajectories: %s}\n" % csv_name)
            f.write("boxes:\n" if self.boxes else "boxes: []\n")
            for cx, cy, sx, sy, sz, yaw, refl, label in self.boxes:
                f.write("  - {center_m: [%g, %g], size_m: [%g, %g, %g], yaw_deg: %g, "
                        "reflectivity: %g}  # %s\n" % (cx, cy, sx, sy, sz, yaw, refl, label))
            f.write("cylinders:\n" if self.cylinders else "cylinders: []\n")
            for cx, cy, rad, h, refl, label in self.cylinders:
                f.write("  - {center_m: [%g, %g], radius_m: %g, height_m: %g, reflectivity: %g}"
                        "  # %s\n" % (cx, cy, rad, h, refl, label))
            f.write("ellipsoids:\n" if self.ellipsoids else "ellipsoids: []\n")
            for cx, cy, cz, rx, ry, rz, refl in self.ellipsoids:
                f.write("  - {center_m: [%g, %g, %g], radii_m: [%g, %g, %g], reflectivity: %g}\n"
                        % (cx, cy, cz, rx, ry, rz, refl))
            f.write("walls:\n" if self.walls else "walls: []\n")
            for x0, y0, x1, y1, h, th, refl in self.walls:
                f.write("  - {from_m: [%g, %g], to_m: [%g, %g], height_m: %g, thickness_m: %g, "
                        "reflectivity: %g}\n" % (x0, y0, x1, y1, h, th, refl))
        rows = 0
        with open(os.path.join(out_dir, csv_name), "w") as f:
            f.write("# %s: %d scripted people, waypoints every %g s; generated by "
                    "scripts/make_validation_scenarios.py\n" % (self.name, len(self.people), SAMPLE_S))
            f.write("# each person exists from its first to its last row; body values on its first row\n")
            f.write("t,id,class,x,y,height_m,width_m,reflectivity\n")
            for p in sorted(self.people, key=lambda q: q["id"]):
                pts = thin(p["samples"])
                for k, (t, x, y) in enumerate(pts):
                    body = ("%g,%g,%g" % (p["height"], p["width"], p["refl"])) if k == 0 else ",,"
                    f.write("%.2f,%d,person,%.3f,%.3f,%s\n" % (t, p["id"], x, y, body))
                    rows += 1
        return rows


def thin(samples):
    """Keeps every SAMPLE_S-th fine sample (and the last), dropping repeated standing rows."""
    step = int(round(SAMPLE_S / FINE_S))
    keep = [s for k, s in enumerate(samples) if k % step == 0]
    if keep[-1] is not samples[-1]:
        keep.append(samples[-1])
    out = [keep[0]]
    for k in range(1, len(keep)):
        prev, cur = out[-1], keep[k]
        nxt = keep[k + 1] if k + 1 < len(keep) else None
        # Drop a row in the middle of a stand (same place before and after).
        if (nxt and (cur[1], cur[2]) == (prev[1], prev[2]) == (nxt[1], nxt[2])):
            continue
        out.append(cur)
    return out


# ---- walking -----------------------------------------------------------------------------------


def rounded_path(points, radius):
    """Polyline with each corner replaced by a circular arc: a dense list of (x, y), ~5 cm apart."""
    pts = [tuple(p) for p in points]
    out = [pts[0]]

    def line_to(p):
        q = out[-1]
        n = max(1, int(math.hypot(p[0] - q[0], p[1] - q[1]) / 0.05))
        for k in range(1, n + 1):
            out.append((q[0] + (p[0] - q[0]) * k / n, q[1] + (p[1] - q[1]) * k / n))

    for i in range(1, len(pts) - 1):
        a, b, c = pts[i - 1], pts[i], pts[i + 1]
        d1 = (b[0] - a[0], b[1] - a[1])
        d2 = (c[0] - b[0], c[1] - b[1])
        l1, l2 = math.hypot(*d1), math.hypot(*d2)
        u1 = (d1[0] / l1, d1[1] / l1)
        u2 = (d2[0] / l2, d2[1] / l2)
        turn = math.atan2(u1[0] * u2[1] - u1[1] * u2[0], u1[0] * u2[0] + u1[1] * u2[1])
        if abs(turn) < 1e-3:
            line_to(b)
            continue
        tangent = min(radius * math.tan(abs(turn) / 2), 0.45 * l1, 0.45 * l2)
        r = tangent / math.tan(abs(turn) / 2)
        p1 = (b[0] - u1[0] * tangent, b[1] - u1[1] * tangent)
        line_to(p1)
        side = 1.0 if turn > 0 else -1.0
        centre = (p1[0] - side * u1[1] * r, p1[1] + side * u1[0] * r)
        a0 = math.atan2(p1[1] - centre[1], p1[0] - centre[0])
        n = max(2, int(abs(turn) * r / 0.05))
        for k in range(1, n + 1):
            ang = a0 + turn * k / n
            out.append((centre[0] + r * math.cos(ang), centre[1] + r * math.sin(ang)))
    line_to(pts[-1])
    return out


def walk(route, speed, t0, rng, radius=2.0, from_stand=True, to_stand=True):
    """Fine samples [(t, x, y)] of walking the rounded route from time t0."""
    path = rounded_path(route, radius)
    cum = [0.0]
    for p, q in zip(path, path[1:]):
        cum.append(cum[-1] + math.hypot(q[0] - p[0], q[1] - p[1]))
    total = cum[-1]
    phase = rng.uniform(0, 2 * math.pi)
    samples = []
    s, v, t, j = 0.0, (0.0 if from_stand else speed), t0, 0
    accel = 1.0
    while True:
        samples.append((round(t, 3), *point_at(path, cum, s, j)))
        if s >= total - 1e-9:
            break
        want = min(MAX_SPEED_MPS, speed * (1.0 + 0.05 * math.sin(phase + 0.6 * (t - t0))))
        if to_stand:
            want = min(want, math.sqrt(2 * accel * max(total - s, 0.0)) + 0.05)
        v = min(want, v + accel * FINE_S) if v < want else max(want, v - 2 * accel * FINE_S)
        s = min(total, s + v * FINE_S)
        while j + 1 < len(cum) and cum[j + 1] < s:
            j += 1
        t += FINE_S
    return samples


def point_at(path, cum, s, j):
    while j + 1 < len(cum) and cum[j + 1] < s:
        j += 1
    if j + 1 >= len(cum):
        return path[-1]
    seg = cum[j + 1] - cum[j]
    u = 0.0 if seg <= 0 else (s - cum[j]) / seg
    return (path[j][0] + u * (path[j + 1][0] - path[j][0]),
            path[j][1] + u * (path[j + 1][1] - path[j][1]))


def stand(xy, t0, t1):
    n = int(round((t1 - t0) / FINE_S))
    return [(round(t0 + k * FINE_S, 3), xy[0], xy[1]) for k in range(n + 1)]


def join(*parts):
    """Concatenates sample lists (a part starting where the previous one ended drops its first)."""
    out = list(parts[0])
    for part in parts[1:]:
        if part and out and abs(part[0][0] - out[-1][0]) < 1e-6:
            part = part[1:]
        out.extend(part)
    return out


def shift(samples, dt):
    return [(round(t + dt, 3), x, y) for t, x, y in samples]


def formation(centre, offsets):
    """Member sample lists at lateral offsets (left positive) from a centre's fine samples."""
    members = [[] for _ in offsets]
    heading = None
    for k, (t, x, y) in enumerate(centre):
        a = centre[max(0, k - 2)]
        b = centre[min(len(centre) - 1, k + 2)]
        if math.hypot(b[1] - a[1], b[2] - a[2]) > 1e-3:
            heading = math.atan2(b[2] - a[2], b[1] - a[1])
        h = heading if heading is not None else 0.0
        nx, ny = -math.sin(h), math.cos(h)
        for m, o in enumerate(offsets):
            members[m].append((t, x + o * nx, y + o * ny))
    return members


def heading_at_end(samples):
    a, b = samples[-4], samples[-1]
    return math.atan2(b[2] - a[2], b[1] - a[1])


def split_route(start_samples, targets):
    """Route from the end of start_samples, first 1.5 m straight on, then through targets."""
    _, x, y = start_samples[-1]
    h = heading_at_end(start_samples)
    return [(x, y), (x + 1.5 * math.cos(h), y + 1.5 * math.sin(h))] + list(targets)


def lateral_offsets(n, rng):
    spacing = rng.uniform(0.55, 0.75)  # centre to centre: 0.5-0.8 m apart
    return [spacing * (k - (n - 1) / 2) for k in range(n)], spacing


# ---- the scenarios -----------------------------------------------------------------------------


def plaza_groups():
    """Open plaza: groups of 2-4 walking side by side, splitting up; a few people alone."""
    sc = Scene("v1-plaza-groups",
               "plaza 60 x 50 m: groups of 2-4 walking side by side (0.5-0.8 m) that split up, "
               "people alone, planters and benches", 70, 101)
    for cx, cy in [(-12, 12), (14, 14), (-14, -13), (15, -12)]:
        sc.box(cx, cy, 3.0, 3.0, 0.7, 0.0, 0.35, "planter")
    for cx, cy, yaw in [(0, 18, 0), (0, -18, 0), (22, 0, 90)]:
        sc.box(cx, cy, 2.0, 0.6, 0.8, yaw, 0.4, "bench")
    for cx, cy in [(-25, 20), (25, 22), (-26, -22), (24, -23)]:
        sc.post(cx, cy, 0.12, 5.0)
    r = sc.rng
    group_id = 0
    # (size, start time, route of the group centre, split time or None, split targets per member)
    groups = [
        (2, 0.0, [(-30, 6), (-8, 6), (6, 8), (30, 9)], None, None),
        (3, 4.0, [(28, -6), (8, -6), (-6, -8), (-30, -7)], 20.0,
         [[(-20, -20), (-31, -21)], [(-30, -9)], [(-8, -4), (-16, 6), (-16, 29)]]),
        (4, 10.0, [(-8, -28), (-8, -9), (-7, 10), (-5, 28)], 22.0,
         [[(-20, 17), (-30, 17)], [(-4, 28)], [(-1, 28)], [(14, 20), (30, 19)]]),
        (2, 18.0, [(30, 4), (12, 3), (-6, 0.5)], 14.0,
         [[(6, 6), (-20, 8), (-31, 12)], [(6, -5), (-9, -10), (-9, -29)]]),
        (3, 30.0, [(-30, -5), (-8, -6), (10, -5), (30, -4)], 12.0,
         [[(6, -6), (20, 6), (31, 10)], [(30, -4)], [(8, -9), (12, -20), (24, -29)]]),
        (2, 40.0, [(4, 29), (5, 8), (8, -10), (9, -29)], None, None),
        (4, 44.0, [(31, 14), (10, 10), (-10, 9), (-31, 8)], 16.0,
         [[(-14, 20), (-24, 29)], [(-30, 11)], [(-30, 8)], [(-20, -2), (-31, -6)]]),
    ]
    for size, t0, route, split_after, targets in groups:
        def make(k, size=size, t0=t0, route=route, split_after=split_after, targets=targets):
            nonlocal group_id
            group_id += 1
            offsets, _ = lateral_offsets(size, r)
            speed = r.uniform(0.95, 1.3)
            centre = walk(route, speed, t0 + 0.7 * k, r, radius=4.0, from_stand=False,
                          to_stand=False)
            if split_after is not None:
                cut = int(split_after / FINE_S)
                centre = centre[:cut]
            members = formation(centre, offsets)
            made = []
            for m, samples in enumerate(members):
                person = sc.new_person(group=group_id)
                if split_after is not None:
                    own = walk(split_route(samples, targets[m]), r.uniform(1.0, 1.5),
                               samples[-1][0], r, radius=2.5, from_stand=False, to_stand=False)
                    samples = join(samples, own)
                samples = [s for s in samples if s[0] <= sc.duration_s]
                made.append((person, samples))
            return made
        add_group(sc, make)
    singles = [
        (2.0, [(-31, -16), (-10, -15), (10, -17), (31, -18)]),
        (12.0, [(20, 29), (19, 10), (17, -29)]),
        (26.0, [(-31, 18), (-8, 15), (10, 17), (31, 19)]),
        (36.0, [(-18, -29), (-19, -4), (-21, 29)]),
        (50.0, [(31, -16), (10, -16.5), (-31, -16)]),
    ]
    for t0, route in singles:
        def make(k, t0=t0, route=route):
            p = sc.new_person()
            s = walk(route, r.uniform(1.0, 1.6), t0 + 0.9 * k, r, radius=3.0, from_stand=False,
                     to_stand=False)
            return p, [q for q in s if q[0] <= sc.duration_s]
        sc.try_add(make)
    return sc


def add_group(sc, make, attempts=30):
    for k in range(attempts):
        made = make(k)
        added = []
        ok = True
        for person, samples in made:
            if not sc.add(person, samples):
                ok = False
                break
            added.append(person)
        if ok:
            return
        for person in added:
            sc.people.remove(person)
            sc.next_id -= 1
    raise SystemExit("%s: no conflict-free group" % sc.name)


def chat_circles():
    """Courtyard: circles of 3-4 people standing and chatting, then walking off; passers-by."""
    sc = Scene("v2-chat-circles",
               "courtyard 50 x 40 m: circles of 3-4 people standing and chatting for most of the "
               "run, then walking off; people arriving, passing and leaving", 90, 202)
    sc.walls.append((-24, 20, 24, 20, 4.0, 0.3, 0.5))
    sc.walls.append((-24, -20, -6, -20, 4.0, 0.3, 0.5))
    sc.walls.append((6, -20, 24, -20, 4.0, 0.3, 0.5))
    for cx, cy in [(-14, 6), (14, 6), (-14, -8), (14, -8)]:
        sc.tree(cx, cy)
    sc.box(0, 17.5, 3, 1.2, 1.0, 0, 0.4, "kiosk counter")
    r = sc.rng
    # (centre, members, chat from, chat until, exits per member)
    circles = [
        ((-7, 9), 4, 0.0, 62.0, [(-22, 16), (-22, 12), (23, 16), (0, -22)]),
        ((8, -5), 3, 0.0, 75.0, [(23, -2), (23, -14), (0, -22)]),
        ((-8, -6), 3, 14.0, 86.0, [(-23, -16), (-2, -22), (-23, -2)]),
        ((9, 10), 4, 8.0, 55.0, [(23, 17), (23, 12), (0, -22), (-22, 2)]),
    ]
    group_id = 100
    for centre, n, t_from, t_until, exits in circles:
        group_id += 1
        radius = r.uniform(0.6, 0.85)  # 0.7-1.2 m between neighbours
        start_angle = r.uniform(0, 2 * math.pi)
        for m in range(n):
            ang = start_angle + 2 * math.pi * m / n + r.uniform(-0.15, 0.15)
            spot = (centre[0] + radius * math.cos(ang), centre[1] + radius * math.sin(ang))
            leave_at = t_until + r.uniform(0, 4)
            outer = (centre[0] + (radius + 1.6) * math.cos(ang),
                     centre[1] + (radius + 1.6) * math.sin(ang))

            def make(k, spot=spot, leave_at=leave_at, outer=outer, m=m, centre=centre,
                     t_from=t_from, exits=exits, group_id=group_id):
                person = sc.new_person(group=group_id)
                if t_from == 0.0:
                    arrive = stand(spot, 0.0, leave_at)
                else:
                    # Arrives from the open south gate, one after the other, from outside the
                    # circle (around it when its place is on the far side).
                    gate = (r.uniform(-3, 3), -22.0)
                    t0 = t_from + 3.0 * m + 1.1 * k
                    side = math.copysign(5.8, centre[0])
                    around = (centre[0] - math.copysign(radius + 1.6, centre[0]), centre[1])
                    via = [around] if (outer[0] - centre[0]) * centre[0] < 0 else []
                    if centre[1] > 0:  # around the sensor's side of the yard
                        approach = [gate, (gate[0], -14), (side, -9), (side, centre[1] - 3)]
                    else:
                        approach = [gate, (gate[0], centre[1] - 5)]
                    approach += via + [outer, spot]
                    w = walk(approach, r.uniform(1.0, 1.3), t0, r, radius=1.2, from_stand=False)
                    arrive = join(w, stand(spot, w[-1][0], leave_at))
                # Leaves: out of the circle, then to its exit.
                leave = walk([spot, outer, exits[m]], r.uniform(1.0, 1.4), arrive[-1][0], r,
                             radius=1.5, to_stand=False)
                return person, [q for q in join(arrive, leave) if q[0] <= sc.duration_s]
            sc.try_add(make, attempts=25)
    passers = [
        (3.0, [(-23, -12), (0, -14), (23, -12)]),
        (11.0, [(0, -22), (-1, -14), (-14, -13), (-23, -14)]),
        (20.0, [(23, 4), (0, 4.2), (-23, 3.5)]),
        (33.0, [(-23, 15), (0, 15), (23, 15)]),
        (41.0, [(23, -13), (2, -14), (-1, -22)]),
        (52.0, [(-23, -2), (0, -3.8), (23, -1.5)]),
        (64.0, [(1, -22), (2, -14), (5.5, -9.5), (5.5, 5), (23, 3.5)]),
    ]
    for t0, route in passers:
        def make(k, t0=t0, route=route):
            p = sc.new_person()
            s = walk(route, r.uniform(0.9, 1.5), t0 + 0.8 * k, r, radius=3.0, from_stand=False,
                     to_stand=False)
            return p, [q for q in s if q[0] <= sc.duration_s]
        sc.try_add(make)
    return sc


def concourse():
    """Dense crossing: two streams of people crossing at right angles, entering and leaving."""
    sc = Scene("v3-concourse",
               "station concourse: two dense streams crossing at right angles (about 20 people in "
               "view), pillars, everyone entering and leaving", 70, 303, sensor_xy=(0.0, -14.0))
    for cx in (-8, 8):
        for cy in (-8, 8):
            sc.box(cx, cy, 0.8, 0.8, 6.0, 0, 0.5, "pillar")
    for cx, cy in [(-14, -3), (14, 3)]:
        sc.post(cx, cy, 0.15, 1.1)
    r = sc.rng
    # Stream A: along x (both directions) in a 4 m wide band about y = 0; stream B along y about
    # x = 0. Lanes are drawn at random and shifted in time until nobody collides.
    t = 0.0
    while t < sc.duration_s - 8:
        for stream in ("A", "B"):
            def make(k, t=t, stream=stream):
                p = sc.new_person()
                lane = r.uniform(-2.0, 2.0)
                sign = 1 if r.random() < 0.5 else -1
                wiggle = r.uniform(-0.8, 0.8)
                if stream == "A":
                    route = [(-22 * sign, lane), (0, lane + wiggle), (22 * sign, lane)]
                else:
                    route = [(lane, -10.5 * sign if sign > 0 else 22), (lane + wiggle, 5),
                             (lane, 22 if sign > 0 else -10.5)]
                s = walk(route, r.uniform(1.1, 1.6), t + 0.4 * k + r.uniform(0, 1.0), r,
                         radius=4.0, from_stand=False, to_stand=False)
                return p, [q for q in s if q[0] <= sc.duration_s]
            sc.try_add(make)
        t += r.uniform(1.6, 2.6)
    return sc


def parking():
    """Car park: people walking behind parked cars and vans and past posts, getting in and out."""
    sc = Scene("v4-parking",
               "car park: rows of cars and vans (boxes), bollards and lamp posts; people walk "
               "behind them, appear beside cars and leave", 75, 404)
    r = sc.rng
    # Row 1 (cars, y = 8), row 2 (vans and cars, y = 18), row 3 across the aisle (x = 24).
    for k, x in enumerate([-16.5, -13.9, -11.3, -6.1, -3.5, -0.9, 4.3, 6.9, 12.1, 14.7]):
        sc.car(x, 8.0)
    for k, x in enumerate([-15.5, -12.7, -7.1, -1.5, 1.3, 6.9, 12.5, 15.3]):
        sc.car(x, 19.0, van=(k % 3 != 1))
    for y in (-4.0, -1.4, 3.8):
        sc.car(24.0, y, along_y=False)
    for x in (-18.5, -8.7, 2.0, 9.5, 17.0):
        sc.post(x, 12.4, 0.1, 1.0)  # bollards along the aisle
    for x in (-10.0, 10.0):
        sc.post(x, 25.5, 0.12, 5.5)  # lamp posts
    # The aisle between the rows runs at y = 13; behind the vans at y = 23.5; in front at y = 4.
    people = [
        # (start, route, stand at end?) - door positions are beside the cars
        (0.0, [(-22, 13.2), (0, 13.5), (22, 13.0)]),
        (3.0, [(9.5, 6.5), (9.6, 11.0), (8.0, 13.4), (-8, 13.6), (-22, 13.5)]),  # gets out of a car
        (6.0, [(-22, 23.5), (0, 23.8), (22, 23.3)]),  # behind the vans
        (9.0, [(22, 23.0), (4.1, 23.5), (4.1, 14.0), (-5, 13.2), (-7.9, 10.9)]),  # to a car
        (14.0, [(-22, 4.5), (-4, 4.0), (19.5, 4.3), (19.8, 12.8), (22, 13.5)]),
        (20.0, [(-4.3, 21.0), (-4.3, 15.5), (-12.5, 13.5), (-22, 14)]),  # from a van
        (25.0, [(22, 13.8), (6, 13.4), (-22, 13.0)]),
        (30.0, [(-22, 23.8), (-10, 23.6), (-9.9, 14.5), (5, 13.2), (22, 13.2)]),
        (37.0, [(19.5, -8), (19.8, 1.5), (17, 4.3), (-22, 4.2)]),
        (44.0, [(-22, 13.4), (-5, 13.6), (1.7, 11.2)]),  # to a car door
        (50.0, [(22, 23.4), (-22, 23.7)]),
        (56.0, [(-22, 4.0), (0, 4.3), (19.5, 4.5), (19.5, -8)]),
    ]
    for t0, route in people:
        def make(k, t0=t0, route=route):
            p = sc.new_person()
            s = walk(route, r.uniform(0.9, 1.5), t0 + 0.8 * k, r, radius=1.8,
                     from_stand=route[0][0] not in (-22, 22),
                     to_stand=route[-1][0] not in (-22, 22))
            return p, [q for q in s if q[0] <= sc.duration_s]
        sc.try_add(make)
    # Two who stand by a van talking, then walk away behind it.
    group = 900
    for m, (spot, exit_route) in enumerate([((13.4, 25.0), [(0, 23.9), (-22, 24)]),
                                            ((14.2, 25.6), [(22, 24.2)])]):
        person = sc.new_person(group=group)
        leave_at = 40.0 + 2.0 * m
        s = join(stand(spot, 0.0, leave_at),
                 walk([spot] + exit_route, r.uniform(1.0, 1.3), leave_at, r, radius=1.5,
                      to_stand=False))
        if not sc.add(person, [q for q in s if q[0] <= sc.duration_s]):
            raise SystemExit("v4: the pair by the van collides with someone")
    return sc


def far_field():
    """Open field with people 30-55 m away (and a few near), trees and a far building."""
    sc = Scene("v5-far-field",
               "open field: people walking 30-55 m from the sensor, a few near ones, trees and a "
               "building far off", 65, 505)
    sc.box(0, 70, 30, 12, 8, 10, 0.45, "building")
    for cx, cy in [(-20, 30), (-28, -35), (35, -20), (48, 12), (-50, 5), (10, -55)]:
        sc.tree(cx, cy)
    r = sc.rng

    def arc(radius, a0_deg, a1_deg, n=8):
        return [(radius * math.cos(math.radians(a0_deg + (a1_deg - a0_deg) * k / n)),
                 radius * math.sin(math.radians(a0_deg + (a1_deg - a0_deg) * k / n)))
                for k in range(n + 1)]

    people = [
        (0.0, arc(34, 100, 175)),  # tangential walks at 34-52 m
        (2.0, arc(44, -60, 10)),
        (5.0, [(30, 40), (38, 28), (50, 20)]),  # walking away, 50 -> 54 m
        (8.0, arc(52, 200, 250)),
        (14.0, [(-55, -5), (-38, -10), (-30, -22)]),  # walking towards, 55 -> 37 m
        (20.0, arc(40, 20, 80)),
        (26.0, [(25, -40), (10, -42), (-12, -44), (-30, -38)]),
        (33.0, arc(47, 130, 190)),
        (40.0, [(45, -25), (42, -6), (36, 14)]),
        # near people for contrast
        (0.0, [(-8, -14), (-6, 8), (10, 12), (14, -10)]),
        (12.0, [(18, 3), (6, -8), (-16, -6)]),
        (30.0, [(-14, 12), (4, 16), (16, 8)]),
    ]
    for t0, route in people:
        def make(k, t0=t0, route=route):
            p = sc.new_person()
            s = walk(route, r.uniform(0.8, 1.5), t0 + 0.9 * k, r, radius=3.0, from_stand=False,
                     to_stand=False)
            return p, [q for q in s if q[0] <= sc.duration_s]
        sc.try_add(make)
    # A pair side by side at about 40 m that stops for a while, then walks on.
    offsets, _ = lateral_offsets(2, r)
    first = walk([(-40, 20), (-36, 5)], 1.0, 6.0, r, radius=3.0, from_stand=False)
    pause = stand(first[-1][1:], first[-1][0], first[-1][0] + 12.0)
    second = walk([first[-1][1:], (-33, -4), (-38, -20)], 1.1, pause[-1][0], r, radius=3.0,
                  to_stand=False)
    centre = join(first, pause, second)
    members = formation(centre, offsets)
    for samples in members:
        p = sc.new_person(group=950)
        if not sc.add(p, [q for q in samples if q[0] <= sc.duration_s]):
            raise SystemExit("v5: pair collides")
    return sc


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "config", "validation")
    os.makedirs(out_dir, exist_ok=True)
    for make in (plaza_groups, chat_circles, concourse, parking, far_field):
        sc = make()
        rows = sc.write(out_dir)
        print("%s: %d people, %d rows, %g s" % (sc.name, len(sc.people), rows, sc.duration_s))


if __name__ == "__main__":
    main()
