#!/usr/bin/env python3
"""Fill the report page's template with a `lagrange.report/1` data file.

    python3 tools/report_page.py SAMPLE.json OUT.html

The same substitution `lagrange report` makes: crates/view/src/report/page.html with
{{style}} = report.css, {{script}} = report.js, {{title}} = the model's name (HTML-escaped)
and {{data}} = the JSON with every "</" written "<\\/" (so that it cannot end its script
element). All placeholders are replaced in one pass, so text inside the data or the
script that looks like a placeholder stays as it is.
"""

import html
import json
import os
import re
import sys

PAGE = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "crates/view/src/report")


def fill(data):
    """The HTML page for one report data object."""
    with open(os.path.join(PAGE, "page.html")) as f:
        template = f.read()
    with open(os.path.join(PAGE, "report.css")) as f:
        style = f.read()
    with open(os.path.join(PAGE, "report.js")) as f:
        script = f.read()
    values = {
        "style": style,
        "script": script,
        "title": html.escape(data.get("name") or "lagrange report"),
        "data": json.dumps(data, separators=(",", ":")).replace("</", "<\\/"),
    }
    return re.sub(r"\{\{(style|script|title|data)\}\}", lambda m: values[m.group(1)], template)


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: report_page.py SAMPLE.json OUT.html")
    with open(sys.argv[1]) as f:
        data = json.load(f)
    with open(sys.argv[2], "w") as f:
        f.write(fill(data))


if __name__ == "__main__":
    main()
