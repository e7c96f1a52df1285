"""The README's Python example runs as written (on a generated mesh in a temporary folder)."""
import os
import pathlib
import re

import seamvox
from conftest import torus

README = pathlib.Path(__file__).resolve().parents[2] / "README.md"


def test_readme_example_runs(tmp_path, capsys):
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)
    assert len(blocks) == 1
    seamvox.write_mesh(str(tmp_path / "scan.ply"), *torus())
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        exec(compile(blocks[0], str(README), "exec"), {})
    finally:
        os.chdir(cwd)
    assert seamvox.check(*seamvox.read_mesh(str(tmp_path / "scan-uv.obj"), uv=True))["seamless"]
    assert "True" in capsys.readouterr().out
