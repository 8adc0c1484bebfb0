"""The README's Python examples run and do what they say."""

import json
import os
import re

import pytest

from conftest import REPO


def python_section_blocks():
    text = (REPO / "README.md").read_text(encoding="utf-8")
    section = text.split("\n## Python\n", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", section, flags=re.S)


def test_the_readme_examples_run(tmp_path, monkeypatch):
    blocks = python_section_blocks()
    assert len(blocks) == 2, "the README's Python section has the example and the plot"
    example, plot = blocks
    assert len(example.strip().splitlines()) == 5
    monkeypatch.chdir(tmp_path)
    namespace = {}
    exec(compile(example, "README example", "exec"), namespace)
    result, truth = namespace["result"], namespace["truth"]
    assert result.outcome == "converged"
    stats = namespace["vicurve"].eval(result.points, truth)
    assert abs(stats["bias"]) < 2e-3 and stats["scatter"] < 2e-2
    assert json.loads((tmp_path / "result.json").read_text())["outcome"]["status"] == "converged"

    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    exec(compile(plot, "README plot", "exec"), namespace)
    assert os.path.getsize(tmp_path / "overlay.png") > 10_000
