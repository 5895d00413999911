"""The guide's Python chapter, run: every ```pycon block of docs/src/python.md
is a doctest, all blocks one session in order, from the repository's root."""

from __future__ import annotations

import doctest
import os
import re

from conftest import ROOT

GUIDE = ROOT / "docs" / "src" / "python.md"


def test_python_chapter_examples():
    text = GUIDE.read_text()
    blocks = re.findall(r"^```pycon\n(.*?)^```", text, flags=re.S | re.M)
    assert len(blocks) >= 8, f"found only {len(blocks)} pycon blocks in {GUIDE}"
    parser = doctest.DocTestParser()
    test = parser.get_doctest("\n".join(blocks), {}, "python.md", str(GUIDE), 0)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        runner.run(test)
    finally:
        os.chdir(cwd)
    result = runner.summarize(verbose=False)
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples of {GUIDE.name} failed (see above)"
