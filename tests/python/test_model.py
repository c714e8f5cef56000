"""Models from Python: files, dicts and generators give the models the CLI reads, and bad
input raises mbsflow.InputError with the CLI's message."""
import glob
import json
import os

import pytest

import mbsflow
from conftest import cli, SOURCE


def examples():
    return sorted(glob.glob(os.path.join(SOURCE, "examples", "models", "*.json")))


@pytest.mark.parametrize("path", examples(), ids=os.path.basename)
def test_file_dict_and_file_again_are_the_same_model(path, tmp_path):
    m = mbsflow.Model.load(path)
    again = mbsflow.Model.from_dict(m.to_dict())
    assert again.to_json() == m.to_json()
    m.save(tmp_path / "saved.json")
    assert mbsflow.Model.load(str(tmp_path / "saved.json")).to_json() == m.to_json()
    assert m.n_bodies == len(m.body_names) == len(m.to_dict()["bodies"])


@pytest.mark.parametrize("kind,py,flags", [
    ("chain", lambda: mbsflow.generate.chain(n=12), ["--bodies", 12]),
    ("grid", lambda: mbsflow.generate.grid(rows=3, cols=4), ["--rows", 3, "--cols", 4]),
    ("train", lambda: mbsflow.generate.train(wagons=2), ["--wagons", 2]),
    ("random", lambda: mbsflow.generate.random(bodies=30, cycles=4, seed=7), ["--bodies", 30, "--cycles", 4, "--seed", 7]),
])
def test_generators_make_the_models_of_mbsflow_generate(kind, py, flags, tmp_path):
    out = tmp_path / f"{kind}.json"
    cli("generate", kind, *flags, "-o", out)
    assert py().to_json() == mbsflow.Model.load(str(out)).to_json()


def bad_models():
    return sorted(glob.glob(os.path.join(SOURCE, "tests", "io", "bad_models", "*.json")))


@pytest.mark.parametrize("path", bad_models(), ids=os.path.basename)
def test_a_bad_model_raises_the_cli_message(path):
    code, _, err = cli("run", path, check=False)
    assert code == 2
    with pytest.raises(mbsflow.InputError) as e:
        mbsflow.run(path)  # read, checked and set up as the CLI does
    assert str(e.value) == err.strip()
    assert isinstance(e.value, ValueError) and isinstance(e.value, mbsflow.Error)


def test_a_bad_dict_raises_naming_the_field():
    d = mbsflow.generate.chain(n=3).to_dict()
    d["bodies"][1]["mass"] = -1.0
    with pytest.raises(mbsflow.InputError, match=r"bodies\[1\]\.mass: must be > 0 \(got -1\)"):
        mbsflow.Model.from_dict(d, name="my_chain")
    d = mbsflow.generate.chain(n=3).to_dict()
    d["joints"][0]["body2"] = "nowhere"
    with pytest.raises(mbsflow.InputError, match="nowhere"):
        mbsflow.Model.from_dict(d)


def test_a_model_built_in_python():
    d = {
        "name": "pendulum",
        "gravity": [0, -9.81, 0],
        "bodies": [{"name": "bob", "mass": 1.0, "inertia": [0.01, 0.01, 0.01, 0, 0, 0], "position": [0, -1, 0]}],
        "joints": [{"name": "pivot", "type": "bushing", "body1": "ground", "body2": "bob", "point2": [0, 1, 0],
                    "stiffness": [1e6, 1e6, 1e6, 0, 0, 0]}],
        "simulation": {"t_end": 1.0, "method": "dopri5"},
    }
    m = mbsflow.Model.from_dict(d)
    assert (m.name, m.n_bodies, m.joint_names, m.method, m.t_end) == ("pendulum", 1, ["pivot"], "dopri5", 1.0)
    assert json.loads(m.to_json())["bodies"][0]["name"] == "bob"
