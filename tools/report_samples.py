#!/usr/bin/env python3
"""Write hand-made `lagrange.report/1` data files for developing the report page.

Until `lagrange report` produces the page's data itself, these samples let the page
and its browser tests run: each one simulates an example with
`lagrange simulate --out`, and computes the positions the page draws from the CSV's
coordinates by the example's own formulas (written out here by hand).

    python3 tools/report_samples.py [LAGRANGE_BINARY] [OUT_DIR]

Defaults: target/debug/lagrange and crates/view/src/report/samples/.
"""

import csv
import json
import math
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DIGITS = 12  # significant digits kept in the samples: they are their own truth


def rounded(values):
    """Round a list of floats to DIGITS significant digits (small files)."""
    return [float(f"{v:.{DIGITS}g}") for v in values]


def simulate(binary, model, until, samples):
    """Run the example; return its CSV columns (name -> list) and the JSON summary."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "run.csv")
        args = [binary, "simulate", os.path.join(ROOT, model), "--until", str(until),
                "--samples", str(samples), "--out", out, "--summary", "json"]
        summary = json.loads(subprocess.run(args, check=True, capture_output=True, text=True).stdout)
        with open(out, newline="") as f:
            rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    columns = {name: [float(row[i]) for row in body] for i, name in enumerate(header)}
    for volatile in ("wall_seconds", "setup_seconds", "derive_seconds"):
        summary.pop(volatile, None)
    return columns, summary


def base(name, dimension, columns, summary, coords, angles, until):
    """The fields every sample shares: time, coordinates and the audited invariants."""
    invariants = summary.get("invariants", {})
    return {
        "format": "lagrange.report/1",
        "name": name,
        "dimension": dimension,
        "derivation": "",
        "until": until,
        "time": rounded(columns["t"]),
        "coordinates": [
            {"name": q, "angle": q in angles, "q": rounded(columns[q]), "qd": rounded(columns[q + "'"])}
            for q in coords
        ],
        "invariants": [
            {"name": n, "conserved": v["conserved"], "values": rounded(columns[n])}
            for n, v in invariants.items() if n in columns
        ],
        "constraint_forces": [],
        "points": [],
        "bodies": [],
        "rods": [],
        "springs": [],
        "summary": summary,
        "events": [],
        "analyses": {},
    }


def point(name, kind, mass, x, y, z=None):
    return {"name": name, "kind": kind, "mass": mass, "x": rounded(x), "y": rounded(y),
            "z": None if z is None else rounded(z)}


def double_pendulum_positions(a, b):
    """examples/double_pendulum.toml with lA = lB = 1."""
    x1, y1 = math.sin(a), -math.cos(a)
    return (x1, y1), (x1 + math.sin(b), y1 - math.cos(b))


def double_pendulum(binary):
    until = 20.0
    cols, summary = simulate(binary, "examples/double_pendulum.toml", until, 501)
    data = base("planar double pendulum", 2, cols, summary, ["a", "b"], {"a", "b"}, until)
    pos = [double_pendulum_positions(a, b) for a, b in zip(cols["a"], cols["b"])]
    data["points"] = [
        point("particle 1", "particle", 1.0, [p[0][0] for p in pos], [p[0][1] for p in pos]),
        point("particle 2", "particle", 1.0, [p[1][0] for p in pos], [p[1][1] for p in pos]),
    ]
    data["rods"] = [[-1, 0], [0, 1]]
    data["derivation"] = (
        "<section><h3>Lagrangian</h3><p><math display=\"block\"><mi>L</mi><mo>=</mo>"
        "<mi>a</mi><msup><mo>′</mo><mn>2</mn></msup><mo>+</mo><mo>…</mo></math></p>"
        "<p>A hand-written stand-in for the derivation.</p></section>")
    # The normal modes about a = b = 0 (from `lagrange modes --at a=0 b=0`).
    frequencies = [2.3971993978640866, 5.787351298036093]
    shapes = [[0.38268343236508984, 0.5411961001461968], [-0.9238795325112865, 1.3065629648763764]]
    frames = []
    for v in shapes:
        scale = 0.35 / max(abs(c) for c in v)
        per_point = [{"x": [], "y": [], "z": None} for _ in range(2)]
        for f in range(64):
            s = scale * math.cos(2 * math.pi * f / 64)
            for i, (x, y) in enumerate(double_pendulum_positions(s * v[0], s * v[1])):
                per_point[i]["x"].append(round(x, 9))
                per_point[i]["y"].append(round(y, 9))
        frames.append(per_point)
    data["analyses"]["modes"] = {
        "frequencies": frequencies, "modes": shapes, "equilibrium": {"a": 0.0, "b": 0.0},
        "coordinates": ["a", "b"], "points": frames,
    }
    return data


def euler_axes(al, be, ga):
    """The rows of D = D_γ·D_β·D_α: the body axes e1, e2, e3 in the fixed frame."""
    sa, ca = math.sin(al), math.cos(al)
    sb, cb = math.sin(be), math.cos(be)
    sg, cg = math.sin(ga), math.cos(ga)
    return (
        [cg * ca - sg * cb * sa, cg * sa + sg * cb * ca, sg * sb],
        [-sg * ca - cg * cb * sa, -sg * sa + cg * cb * ca, cg * sb],
        [sb * sa, -sb * ca, cb],
    )


def heavy_top(binary):
    until = 10.0
    cols, summary = simulate(binary, "examples/tops/heavy_top.toml", until, 501)
    data = base("heavy symmetric top", 3, cols, summary, ["al", "be", "ga"], {"al", "be", "ga"}, until)
    n = len(cols["t"])
    axes = [euler_axes(a, b, g) for a, b, g in zip(cols["al"], cols["be"], cols["ga"])]
    data["points"] = [point("top", "body", 1.0, [0.0] * n, [0.0] * n, [0.0] * n)]
    data["bodies"] = [{
        "name": "top", "point": 0, "length": 1.0,
        "axes": [[[float(f"{c:.{DIGITS}g}") for c in row[k]] for row in axes] for k in range(3)],
    }]
    e3 = [row[2] for row in axes]
    data["analyses"]["top"] = {
        "beta_min": 0.6, "beta_max": 0.8255432365496063,
        "axis": {"x": rounded([e[0] for e in e3]), "y": rounded([e[1] for e in e3]),
                 "z": rounded([e[2] for e in e3])},
    }
    return data


def kepler(binary):
    until = 30.0
    cols, summary = simulate(binary, "examples/kepler.toml", until, 601)
    data = base("Kepler problem", 2, cols, summary, ["r", "th"], {"th"}, until)
    x = [r * math.cos(t) for r, t in zip(cols["r"], cols["th"])]
    y = [r * math.sin(t) for r, t in zip(cols["r"], cols["th"])]
    data["points"] = [point("relative position", "particle", 1.0, x, y)]
    l, k = 1.2, 1.0
    radii = [0.5 + i * (4.0 - 0.5) / 199 for i in range(200)]
    data["analyses"]["orbit"] = {
        "kind": "ellipse", "periapsis": 1.0, "apoapsis": 2.571428571428571, "energy": -0.28,
        "u_eff": {"r": rounded(radii), "u": rounded([l * l / (2 * r * r) - k / r for r in radii])},
    }
    data["events"] = [{"t": t, "label": "periapsis"} for t in (0.0, 14.993320610381373, 29.986641220762746)]
    return data


def pendulum_cartesian(binary):
    until = 5.0
    cols, summary = simulate(binary, "examples/constraints/pendulum_cartesian.toml", until, 251)
    data = base("pendulum in Cartesian coordinates", 2, cols, summary, ["x", "y"], set(), until)
    data["points"] = [point("particle 1", "particle", 1.0, cols["x"], cols["y"])]
    data["rods"] = [[-1, 0]]
    data["constraint_forces"] = [{"name": "rod", "values": rounded(cols["force_rod"])}]
    return data


def spherical_pendulum(binary):
    """3-D: a particle on a rod, with an azimuth that runs far (wrapped in the plots)."""
    until = 12.0
    cols, summary = simulate(binary, "examples/spherical_pendulum.toml", until, 601)
    data = base("spherical pendulum", 3, cols, summary, ["th", "ph"], {"th", "ph"}, until)
    th, ph = cols["th"], cols["ph"]
    data["points"] = [point(
        "bob", "particle", 1.0,
        [math.sin(a) * math.cos(b) for a, b in zip(th, ph)],
        [math.sin(a) * math.sin(b) for a, b in zip(th, ph)],
        [-math.cos(a) for a in th],
    )]
    data["rods"] = [[-1, 0]]
    return data


def triatomic(binary):
    """Three masses on a line joined by springs; its modes include a drift (frequency 0)."""
    until = 40.0
    cols, summary = simulate(binary, "examples/triatomic.toml", until, 401)
    names = ["q1", "q2", "q3"]
    data = base("linear triatomic molecule", 2, cols, summary, names, set(), until)
    masses = [16.0, 12.0, 16.0]
    data["points"] = [
        point(f"atom {i + 1}", "particle", masses[i], [i + v for v in cols[q]], [0.0] * len(cols[q]))
        for i, q in enumerate(names)
    ]
    data["springs"] = [[0, 1], [1, 2]]
    frequencies = [0.0, 0.2499999999999999, 0.47871355387816905]
    shapes = [[0.15075567228888184, 0.1507556722888818, 0.15075567228888176],
              [0.17677669529663684, 0.0, -0.1767766952966369],
              [-0.09231861823449952, 0.24618298195866548, -0.09231861823449952]]
    frames = []
    for omega, v in zip(frequencies, shapes):
        scale = 0.3 / max(abs(c) for c in v)
        per_point = [{"x": [], "y": [], "z": None} for _ in names]
        for f in range(64):
            # a drift moves steadily one way; an oscillation goes once round its cycle
            s = scale * (f / 63 if omega == 0 else math.cos(2 * math.pi * f / 64))
            for i in range(3):
                per_point[i]["x"].append(round(i + s * v[i], 9))
                per_point[i]["y"].append(0.0)
        frames.append(per_point)
    data["analyses"]["modes"] = {
        "frequencies": frequencies, "modes": shapes, "equilibrium": {q: 0.0 for q in names},
        "coordinates": names, "points": frames,
    }
    return data


def empty(_binary):
    """The least a page can receive: no rows, no coordinates, nothing to draw."""
    return {
        "format": "lagrange.report/1", "name": "empty <run> & nothing else", "dimension": 2,
        "derivation": "", "until": 0.0, "time": [], "coordinates": [], "invariants": [],
        "constraint_forces": [], "points": [], "bodies": [], "rods": [], "springs": [],
        "summary": {}, "events": [], "analyses": {},
    }


def main():
    binary = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "target/debug/lagrange")
    out_dir = sys.argv[2] if len(sys.argv) > 2 else os.path.join(ROOT, "crates/view/src/report/samples")
    os.makedirs(out_dir, exist_ok=True)
    for name, make in [("double_pendulum", double_pendulum), ("heavy_top", heavy_top),
                       ("kepler", kepler), ("pendulum_cartesian", pendulum_cartesian),
                       ("spherical_pendulum", spherical_pendulum), ("triatomic", triatomic), ("empty", empty)]:
        path = os.path.join(out_dir, name + ".json")
        with open(path, "w") as f:
            json.dump(make(binary), f, separators=(",", ":"))
            f.write("\n")
        print(f"{path}: {os.path.getsize(path)} bytes")


if __name__ == "__main__":
    main()
