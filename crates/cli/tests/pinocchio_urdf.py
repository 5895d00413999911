#!/usr/bin/env python3
"""URDF robots through `lagrange import` + `lagrange derive`, checked against Pinocchio.

For each URDF: `lagrange import` writes the model, `lagrange derive --format json`
prints M(q) and the forcing f(q, q') of M q'' = f; both are evaluated at random
states (the expressions are in lagrange's syntax, evaluated with Python's math) and
compared with Pinocchio's mass matrix (crba) and bias forces (nonLinearEffects,
which is -f: M q'' + nle = 0 without actuation), to a relative tolerance (default
1e-10, relative to the largest entry of M, and of f).

Coordinates map one to one: a revolute or prismatic joint is Pinocchio's q and v; a
continuous joint is q = (cos th, sin th), v = th'; a floating base (--floating-base, or
a floating joint from the root link) is Pinocchio's root joint built as the composite
PX, PY, PZ, RX, RY, RZ, the same x, y, z, roll, pitch, yaw (turns about x, the new y,
the newest z) that lagrange gives it, so q' = v there too.

Usage:
  pinocchio_urdf.py --lagrange target/debug/lagrange examples/urdf/*.urdf
  pinocchio_urdf.py --lagrange BIN panda ur5 --timeout 120
  pinocchio_urdf.py --lagrange BIN talos --floating-base
Robot names (panda, ur5, talos, g1) are the URDFs that the example-robot-data package
ships. Exit 0 when every robot agrees, 1 when one does not or fails, 77 when
Pinocchio is not installed (a test runner's "skipped").
"""

import argparse
import glob
import math
import os
import random
import re
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET

ROBOTS = {
    "panda": "panda_description/urdf/panda.urdf",
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "talos": "talos_data/robots/talos_reduced.urdf",
    "g1": "g1_description/urdf/g1_29dof_rev_1_0.urdf",
}

_ACCELERATION = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)''")
_VELOCITY = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)'")


def _to_python(expr: str) -> str:
    expr = _ACCELERATION.sub(r"\1__ddot", expr)
    return _VELOCITY.sub(r"\1__dot", expr).replace("^", "**")


def identifier(name: str) -> str:
    """The coordinate name `lagrange import` gives a joint (when no other takes it)."""
    return re.sub(r"[^A-Za-z0-9]", "_", name)


def robot_path(name: str) -> str:
    if os.path.exists(name):
        return name
    rel = ROBOTS.get(name)
    if rel is None:
        sys.exit(f"{name}: not a file, and not one of {', '.join(ROBOTS)}")
    for site in sys.path:
        hits = glob.glob(os.path.join(site, "cmeel.prefix", "share", "example-robot-data", "robots", rel))
        if hits:
            return hits[0]
    sys.exit(f"{name}: example-robot-data is not installed (pip install example-robot-data)")


def free_root(pin):
    joint = pin.JointModelComposite()
    for j in (pin.JointModelPX(), pin.JointModelPY(), pin.JointModelPZ(),
              pin.JointModelRX(), pin.JointModelRY(), pin.JointModelRZ()):
        joint.addJoint(j)
    return joint


def pinocchio_model(pin, path: str, floating_base: bool):
    """Pinocchio's model and the names of the six base coordinates' prefix (or None)."""
    tree = ET.parse(path)
    robot = tree.getroot()
    children = {j.find("child").get("link") for j in robot.findall("joint")}
    roots = [link.get("name") for link in robot.findall("link") if link.get("name") not in children]
    floating = [j for j in robot.findall("joint") if j.get("type") == "floating"]
    if floating:
        # lagrange's floating joint is x, y, z, roll, pitch, yaw: give Pinocchio the
        # same as the root joint of the URDF without that joint and its world link.
        (j,) = floating
        origin = j.find("origin")
        if origin is not None and any(float(x) != 0 for x in (origin.get("rpy") or "0 0 0").split()):
            sys.exit(f"{path}: this check takes a floating joint with no rotation in its origin")
        if j.find("parent").get("link") != roots[0]:
            sys.exit(f"{path}: this check takes a floating joint from the root link only")
        robot.remove(j)
        for link in robot.findall("link"):
            if link.get("name") == roots[0]:
                robot.remove(link)
        model = pin.buildModelFromXML(ET.tostring(robot, encoding="unicode"), free_root(pin))
        return model, identifier(j.get("name"))
    if floating_base:
        return pin.buildModelFromUrdf(path, free_root(pin)), identifier(roots[0])
    return pin.buildModelFromUrdf(path), None


def check(binary: str, path: str, floating_base: bool, states: int, seed: int, tol: float, timeout: float) -> bool:
    import numpy as np
    import pinocchio as pin

    label = os.path.basename(path)
    with tempfile.TemporaryDirectory() as tmp:
        toml = os.path.join(tmp, "robot.toml")
        cmd = [binary, "import", path, "-o", toml] + (["--floating-base"] if floating_base else [])
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            print(f"{label}: import failed (exit {proc.returncode}):\n{proc.stderr}")
            return False
        t0 = time.perf_counter()
        try:
            proc = subprocess.run([binary, "derive", "--format", "json", toml], capture_output=True, text=True,
                                  timeout=timeout)
        except subprocess.TimeoutExpired:
            print(f"{label}: derive did not finish within {timeout:g} s")
            return False
        wall = time.perf_counter() - t0
    if proc.returncode != 0:
        print(f"{label}: derive failed (exit {proc.returncode}):\n{proc.stderr[-3000:]}")
        return False
    import json

    out = json.loads(proc.stdout)
    coords = out["coordinates"]
    # A large model's results name their shared subexpressions: evaluated in order first.
    definitions = [(d["name"], compile(_to_python(d["expr"]), d["name"], "eval")) for d in out.get("definitions") or []]
    mass = [[compile(_to_python(e), "M", "eval") for e in row] for row in out["mass_matrix"]]
    forcing = [compile(_to_python(e), "f", "eval") for e in out["forcing"]]
    namespace = {name: getattr(math, name) for name in ("sin", "cos", "tan", "sqrt", "exp", "log", "pi")}
    for name, value in (out.get("parameters") or {}).items():
        namespace[name] = float(value["value"] if isinstance(value, dict) else value)

    model, base = pinocchio_model(pin, path, floating_base)
    data = model.createData()
    n = len(coords)
    if model.nv != n:
        print(f"{label}: Pinocchio has {model.nv} velocities, lagrange {n} coordinates")
        return False
    # Each lagrange coordinate: (index in v, index in q, nq of its joint, offset in the joint).
    where = {}
    for j in range(1, model.njoints):
        joint = model.joints[j]
        name = model.names[j]
        if joint.nv == 6 and base is not None:
            for k, suffix in enumerate(("x", "y", "z", "roll", "pitch", "yaw")):
                where[f"{base}_{suffix}"] = (joint.idx_v + k, joint.idx_q + k, 1)
        elif joint.nv == 1:
            where[identifier(name)] = (joint.idx_v, joint.idx_q, joint.nq)
        else:
            print(f"{label}: Pinocchio joint {name} has {joint.nv} velocities; this check maps 1 or a base of 6")
            return False
    missing = [c for c in coords if c not in where]
    if missing:
        print(f"{label}: no Pinocchio joint for the coordinates {missing}")
        return False
    order = [where[c][0] for c in coords]

    rng = random.Random(seed)
    worst_m, worst_f = 0.0, 0.0
    for _ in range(states):
        values = {c: rng.uniform(-math.pi, math.pi) for c in coords}
        rates = {c: rng.uniform(-2.0, 2.0) for c in coords}
        env = dict(namespace)
        q = pin.neutral(model)
        v = np.zeros(model.nv)
        for c in coords:
            env[c] = values[c]
            env[c + "__dot"] = rates[c]
            env[c + "__ddot"] = 0.0  # in definitions the equations share, not in M or f
            iv, iq, nq = where[c]
            if nq == 2:
                q[iq], q[iq + 1] = math.cos(values[c]), math.sin(values[c])
            else:
                q[iq] = values[c]
            v[iv] = rates[c]
        for name, code in definitions:
            env[name] = eval(code, {"__builtins__": {}}, env)
        m = np.array([[eval(e, {"__builtins__": {}}, env) for e in row] for row in mass], float)
        f = np.array([eval(e, {"__builtins__": {}}, env) for e in forcing], float)
        m_pin = pin.crba(model, data, q).copy()
        m_pin = np.triu(m_pin) + np.triu(m_pin, 1).T
        nle = pin.nonLinearEffects(model, data, q, v).copy()
        m_pin = m_pin[np.ix_(order, order)]
        nle = nle[order]
        worst_m = max(worst_m, float(np.abs(m - m_pin).max() / np.abs(m_pin).max()))
        worst_f = max(worst_f, float(np.abs(f + nle).max() / max(np.abs(nle).max(), 1e-300)))
    ok = worst_m <= tol and worst_f <= tol
    print(f"{label}: {n} coordinates, derive {wall:.2f} s; over {states} states max |M - M_pin|/max|M_pin| = "
          f"{worst_m:.2e}, max |f + nle_pin|/max|nle_pin| = {worst_f:.2e}: {'agree' if ok else 'DIFFER'} "
          f"(tolerance {tol:g})")
    return ok


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("robots", nargs="+", help="URDF files, or panda, ur5, talos, g1 from example-robot-data")
    parser.add_argument("--lagrange", required=True, help="the lagrange binary")
    parser.add_argument("--floating-base", action="store_true", help="give the root link six coordinates")
    parser.add_argument("--states", type=int, default=20)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--tol", type=float, default=1e-10)
    parser.add_argument("--timeout", type=float, default=600.0, help="seconds for one derive")
    args = parser.parse_args()
    try:
        import numpy  # noqa: F401
        import pinocchio  # noqa: F401
    except ImportError as e:
        print(f"skipped: {e} (pip install pin example-robot-data numpy)")
        sys.exit(77)
    ok = True
    for name in args.robots:
        ok &= check(args.lagrange, robot_path(name), args.floating_base, args.states, args.seed, args.tol,
                    args.timeout)
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
