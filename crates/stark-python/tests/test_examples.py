"""Every example runs (briefly) and the README's Python examples run as written."""

import importlib.util
import os
import re
from pathlib import Path

import pytest

from conftest import REPO

EXAMPLES = sorted((REPO / "crates" / "stark-python" / "examples").glob("*.py"))


def load(path):
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_five_examples_exist():
    assert {p.stem for p in EXAMPLES} >= {
        "hello_world", "boxes_on_cloth", "twisting_cloth", "inflation", "viscoelasticity"}


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_example_runs(path, tmp_path, capsys):
    module = load(path)
    assert module.__doc__ and "--duration" in module.__doc__
    sim = module.main(["--duration", "0.1", "--out", str(tmp_path)])
    assert sim.time == pytest.approx(0.1)
    assert "steps" in capsys.readouterr().out
    assert any(f.endswith(".vtu") for f in os.listdir(tmp_path))
    assert sim.find_intersections() == []


def test_readme_python_examples_run_as_written(tmp_path, monkeypatch):
    # The Python section's snippets, in order, in one namespace (the joint one continues the first).
    readme = (REPO / "README.md").read_text()
    section = readme[readme.index("## Python"):]
    section = section[:section.index("\n## ", 1)]
    snippets = re.findall(r"```python\n(.*?)```", section, re.S)
    assert len(snippets) == 2
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "__main__"}
    for code in snippets:
        exec(compile(code, "README.md", "exec"), namespace)
    assert Path("output").exists()
    assert namespace["sim"].joint_state(namespace["motor"]).coordinate == pytest.approx(0.5, rel=0.02)
