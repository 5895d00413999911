#!/usr/bin/env python3
"""The positions a report page draws, against the run's CSV.

For every NAME.html in FOLDER whose browser test wrote NAME.positions.json (the
positions `window.lagrangeReport.positions()` gave at a row's time) and whose
run wrote NAME.csv (`lagrange simulate` with the report's --until and
--samples): the row of the CSV at that time holds the same coordinates as the
page's data, and the page drew every point where the data places it at that
row, to 1e-9. (That the data places the points where the model does, x_i(q, t),
is checked against the notes' formulas by crates/cli/tests/report.rs.)

    python3 tests/browser/compare_positions.py FOLDER
"""

import csv
import json
import re
import sys
from pathlib import Path

TOLERANCE = 1e-9


def page_data(page: Path) -> dict:
    html = page.read_text()
    m = re.search(r'<script type="application/json" id="lagrange-data">(.*?)</script>', html, re.S)
    if not m:
        raise SystemExit(f"{page}: no lagrange-data element")
    return json.loads(m.group(1).replace("<\\/", "</"))


def check(page: Path) -> str:
    shown = json.loads(page.with_suffix(".positions.json").read_text())
    data = page_data(page)
    t = shown["time"]
    times = data["time"]
    if t not in times:
        raise AssertionError(f"{page.name}: t = {t} is not a row's time")
    k = times.index(t)
    with open(page.with_suffix(".csv")) as f:
        rows = list(csv.reader(f))
    header, table = rows[0], [r for r in rows[1:]]
    match = [r for r in table if float(r[0]) == t]
    if not match:
        raise AssertionError(f"{page.name}: the CSV has no row at t = {t}")
    row = match[0]
    for c in data["coordinates"]:
        got, want = c["q"][k], float(row[header.index(c["name"])])
        if abs(got - want) > TOLERANCE * max(1.0, abs(want)):
            raise AssertionError(f"{page.name}: {c['name']} = {got} in the page, {want} in the CSV at t = {t}")
    if len(shown["positions"]) != len(data["points"]):
        raise AssertionError(f"{page.name}: {len(shown['positions'])} positions drawn, {len(data['points'])} points")
    for p, point in zip(shown["positions"], data["points"]):
        for axis in ("x", "y", "z"):
            if point.get(axis) is None:
                continue
            got, want = p[axis], point[axis][k]
            if abs(got - want) > TOLERANCE * max(1.0, abs(want)):
                raise AssertionError(f"{page.name}: {point['name']}.{axis} drawn at {got}, placed at {want} (t = {t})")
    return f"{page.name}: {len(shown['positions'])} points at t = {t} match"


def main() -> int:
    folder = Path(sys.argv[1])
    pages = sorted(p for p in folder.glob("*.html") if p.with_suffix(".positions.json").exists())
    if not pages:
        print(f"no pages with positions in {folder}", file=sys.stderr)
        return 1
    failed = 0
    for page in pages:
        try:
            print(check(page))
        except AssertionError as e:
            failed += 1
            print(f"FAILED {e}", file=sys.stderr)
    print(f"{len(pages) - failed} of {len(pages)} pages draw the run's positions")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
