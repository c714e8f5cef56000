"""docs/first-model.md runs as written: its model files are written where it names them
(```json NAME), its shell blocks run (with this build's mbsflow on PATH) and its Python
blocks execute, in the page's order, in one scratch folder."""
import json
import os
import re
import subprocess

from conftest import EXE, SOURCE


def blocks():
    text = open(os.path.join(SOURCE, "docs", "first-model.md")).read()
    return re.findall(r"```(json|sh|python)([^\n]*)\n(.*?)```", text, re.S)


def test_every_block_of_the_first_model_page_runs(tmp_path, monkeypatch):
    found = blocks()
    kinds = [k for k, _, _ in found]
    assert kinds.count("json") >= 2 and kinds.count("sh") >= 5 and kinds.count("python") >= 2
    env = dict(os.environ, MBSFLOW=os.path.abspath(SOURCE),
               PATH=os.path.dirname(os.path.abspath(EXE)) + os.pathsep + os.environ["PATH"])
    monkeypatch.chdir(tmp_path)
    namespace = {}
    for kind, name, body in found:
        if kind == "json":
            assert name.strip(), "a model file block names its file: ```json NAME"
            (tmp_path / name.strip()).write_text(body)
        elif kind == "sh":
            # The set-up block's lines (the repository's root, the folder) are the test's own.
            lines = [l for l in body.splitlines() if not l.startswith(("export ", "mkdir -p first-model"))]
            for line in lines:
                p = subprocess.run(["bash", "-c", line], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
                assert p.returncode == 0, f"{line}: exit {p.returncode}\n{p.stderr}"
                if line.startswith("mbsflow run pendulum.json"):
                    # one clear line on the method chosen, and no "give --step"
                    assert "no joint gives RK4 a stable step" in p.stderr and "dopri5" in p.stderr, p.stderr
                if line.startswith("mbsflow run chain.json"):
                    assert "RK4 with the stability estimate" in p.stderr, p.stderr
        else:
            exec(compile(body, "docs/first-model.md", "exec"), namespace)
    for produced in ("pendulum.h5", "pendulum.png", "pendulum.html", "double_pendulum.png", "chain.html", "slider_crank.h5"):
        assert (tmp_path / produced).stat().st_size > 1000, produced


def test_every_json_block_of_the_docs_parses_and_every_whole_model_runs(tmp_path):
    files = [os.path.join(SOURCE, "README.md")] + sorted(
        os.path.join(SOURCE, "docs", f) for f in os.listdir(os.path.join(SOURCE, "docs")) if f.endswith(".md"))
    models = 0
    for path in files:
        for info, body in re.findall(r"```json([^\n]*)\n(.*?)```", open(path).read(), re.S):
            document = json.loads(body)  # fragments too: each is a JSON value as written
            if isinstance(document, dict) and "bodies" in document:
                model = tmp_path / "model.json"
                model.write_text(body)
                p = subprocess.run([EXE, "run", str(model), "--t-end", "0.01", "-q"], capture_output=True, text=True,
                                   timeout=300)
                assert p.returncode == 0, f"{path}: {p.stderr}"
                models += 1
    assert models >= 3
