"""The README's Python code runs as written: every ```python block of
README.md, in order, in one namespace (as a reader pastes them into one
session), in a folder of its own. A snippet that uses a name it never
defined (`u` in the first one did) or an argument the package does not take
fails here."""

import os
import pathlib
import re

README = pathlib.Path(__file__).resolve().parents[2] / "README.md"


def blocks():
    text = README.read_text()
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


def test_every_python_block_of_the_readme_runs(tmp_path):
    found = blocks()
    assert len(found) >= 3, "the README's Python examples were not found"
    namespace = {"__name__": "readme"}
    here = os.getcwd()
    os.chdir(tmp_path)
    try:
        for k, code in enumerate(found):
            exec(compile(code, f"README.md python block {k + 1}", "exec"), namespace)
    finally:
        os.chdir(here)
    # What the blocks say they produce.
    assert (tmp_path / "work_precision.svg").is_file()
    assert (tmp_path / "my-benchmark" / "benchmark.csv").is_file()
