"""The Python examples of docs/python.md run as written (in order, in one namespace, in a
scratch folder), so the documentation cannot drift from the package."""
import os
import re
import subprocess

from conftest import SOURCE


def blocks():
    text = open(os.path.join(SOURCE, "docs", "python.md")).read()
    return re.findall(r"```python\n(.*?)```", text, re.S)


def test_the_python_examples_of_the_docs_run(tmp_path, monkeypatch):
    code = blocks()
    assert len(code) >= 4
    # the compiled right-hand side the example loads
    (tmp_path / "vdp.c").write_text("void vdp(double t, const double* y, double* dy) {\n"
                                    "  (void)t; dy[0] = y[1]; dy[1] = ((1 - y[0] * y[0]) * y[1] - y[0]) / 1e-6;\n}\n")
    subprocess.run(["cc", "-O2", "-shared", "-fPIC", "-o", str(tmp_path / "vdp.so"), str(tmp_path / "vdp.c")], check=True)
    monkeypatch.chdir(tmp_path)
    namespace = {}
    for block in code:
        exec(compile(block, "docs/python.md", "exec"), namespace)
    assert (tmp_path / "double_pendulum.png").stat().st_size > 10000
    assert abs(namespace["math"].atan2(namespace["bob"][0], -namespace["bob"][1]) - 0.6) < 1e-3
    assert namespace["sol"].success
