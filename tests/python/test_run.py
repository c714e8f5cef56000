"""mbsflow.run gives the CLI's numbers, bit for bit, in every mode; results read back from
files of every kind."""
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

import mbsflow
from conftest import cli

SERIES = ["position", "orientation", "velocity", "angular_velocity", "energy", "body_energy"]


@pytest.fixture(scope="module")
def chain(tmp_path_factory):
    path = tmp_path_factory.mktemp("chain") / "chain.json"
    cli("generate", "chain", "--bodies", 24, "--t-end", 0.05, "-o", path)
    return path


@pytest.mark.parametrize("flags,kwargs", [
    (["--method", "dopri5", "--threads", 1], dict(method="dopri5", threads=1)),
    (["--method", "rk4", "--threads", 2, "--partitions", 3, "--output-interval", 0.005],
     dict(method="rk4", threads=2, partition=3, output_interval=0.005)),
    (["--method", "dopri5", "--coupling", "loose", "--threads", 2], dict(method="dopri5", coupling="loose", threads=2)),
    (["--method", "tirk", "--rtol", 1e-4, "--atol", 1e-6, "--threads", 2],
     dict(method="tirk", rtol=1e-4, atol=1e-6, threads=2)),
    (["--method", "rk4", "--output-interval", 0.01, "--fields", "all"], dict(method="rk4", output_interval=0.01, fields="all")),
], ids=["dopri5", "rk4-partitions", "loose", "tirk", "rk4-all-fields"])
def test_python_runs_are_the_cli_runs_bit_for_bit(chain, tmp_path, flags, kwargs):
    cli("run", chain, "-o", tmp_path / "cli.h5", "-q", *flags)
    ref = mbsflow.Results.open(tmp_path / "cli.h5")
    got = mbsflow.run(mbsflow.Model.load(str(chain)), **kwargs)  # in memory
    assert got.path is None and len(got.t) == len(ref.t) > 2
    assert np.array_equal(got.t, ref.t)
    names = SERIES + (["joint_wrench", "attachment"] if kwargs.get("fields") == "all" else [])
    for name in names:
        assert np.array_equal(getattr(got, name), getattr(ref, name)), name
    assert got.body_names == ref.body_names and got.joint_names == ref.joint_names
    assert got.summary["snapshots"] == len(ref.t)


def test_results_of_a_file_run_and_of_an_ode_run(chain, tmp_path):
    r = mbsflow.run(str(chain), method="dopri5", output=tmp_path / "py.h5", fields="all")
    assert os.path.exists(tmp_path / "py.h5") and r.path == str(tmp_path / "py.h5")
    again = mbsflow.Results.open(tmp_path / "py.h5")
    assert not again.live and not again.ode
    assert again.position.shape == (len(again.t), 24, 3)
    assert np.array_equal(again.joint_force, again.joint_wrench[:, :, :3])
    # energy series sum up: per-body kinetic energies give the model's
    assert np.allclose(again.body_energy[:, :, 0].sum(axis=1), again.energy[:, 0], rtol=1e-12, atol=1e-12)
    b = again.body(again.body_names[3])
    assert np.array_equal(b["position"], again.position[:, 3])
    files = again.export_csv(tmp_path / "csv")
    assert any(f.endswith("energy.csv") for f in files)
    cli("ode", "--problem", "vdp", "--method", "tirk", "--tol", 1e-6, "-q", "-o", tmp_path / "ode.h5")
    ode = mbsflow.Results.open(tmp_path / "ode.h5")
    assert ode.ode and ode.y.shape[0] == len(ode.t) and ode.t[-1] == pytest.approx(2.0)


def test_bad_settings_raise_with_the_setting_named(chain):
    m = mbsflow.Model.load(str(chain))
    with pytest.raises(mbsflow.InputError, match=r"method=euler: unknown method \(rk4, dopri5, colloc, tirk\)"):
        mbsflow.run(m, method="euler")
    with pytest.raises(mbsflow.InputError, match="macro_step.*only with coupling=loose"):
        mbsflow.run(m, macro_step=0.01)
    with pytest.raises(mbsflow.InputError, match="t_end: must be > t_start"):
        mbsflow.run(m, t_end=-1)


def test_a_diverging_run_raises_run_error(chain):
    m = mbsflow.Model.load(str(chain))
    with pytest.raises(mbsflow.RunError, match="diverged") as e:
        mbsflow.run(m, method="rk4", step=5e-3)
    assert isinstance(e.value, RuntimeError)


def test_the_gil_is_released_while_a_run_goes(chain):
    m = mbsflow.generate.chain(n=400, t_end=0.5)
    counted = []
    done = threading.Event()

    def count():
        n = 0
        while not done.is_set():
            n += 1
        counted.append(n)

    t = threading.Thread(target=count)
    t.start()
    start = time.perf_counter()
    r = mbsflow.run(m, method="rk4", threads=1, output_every=50)
    wall = time.perf_counter() - start
    done.set()
    t.join()
    assert wall > 0.1 and r.summary["steps"] > 100
    # A thread held off by the GIL for the whole run would count a handful of times.
    assert counted[0] > 10000


def test_ctrl_c_stops_a_run_and_keeps_its_file(tmp_path):
    script = textwrap.dedent(f"""
        import os, signal, threading, mbsflow
        m = mbsflow.generate.chain(n=2000, t_end=100.0)
        threading.Timer(1.5, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
        try:
            mbsflow.run(m, method="rk4", threads=1, output={str(tmp_path / 'stopped.h5')!r}, output_every=20)
            print("not interrupted")
        except KeyboardInterrupt:
            r = mbsflow.Results.open({str(tmp_path / 'stopped.h5')!r})
            print("interrupted", len(r.t), r.t[-1])
        # Python's own handler is back: a second Ctrl-C is a KeyboardInterrupt in Python code
        try:
            os.kill(os.getpid(), signal.SIGINT)
            import time; time.sleep(1)
            print("no interrupt")
        except KeyboardInterrupt:
            print("python handler back")
    """)
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300,
                       env=dict(os.environ))
    assert p.returncode == 0, p.stderr
    lines = p.stdout.split("\n")
    words = lines[0].split()
    assert words[0] == "interrupted" and int(words[1]) >= 1 and 0 < float(words[2]) < 100.0
    assert lines[1] == "python handler back"


def test_results_of_a_run_still_going(tmp_path):
    model = tmp_path / "long.json"
    cli("generate", "chain", "--bodies", 1500, "--t-end", 50, "-o", model)
    out = tmp_path / "live.h5"
    run = subprocess.Popen([os.environ.get("MBSFLOW_EXE", "mbsflow"), "run", str(model), "-o", str(out), "-q",
                            "--threads", "1", "--output-interval", "0.001"])
    try:
        deadline = time.monotonic() + 120
        r = None
        while time.monotonic() < deadline:
            try:
                r = mbsflow.Results.open(out)
                if len(r.t) >= 2:
                    break
            except mbsflow.InputError:
                pass  # not created yet
            time.sleep(0.2)
        assert r is not None and r.live
        first = len(r.t)
        assert r.position.shape[0] >= first and r.position.shape[1:] == (1500, 3)
        time.sleep(2.0)
        assert len(r.refresh().t) > first  # the run went on, and the refreshed results show it
    finally:
        run.send_signal(signal.SIGINT)
        assert run.wait(timeout=120) == 1  # stopped: exit code 1, results kept
    # Released first: while this process holds the file open, HDF5 hands out that open file
    # (the live view) to a new open too.
    r = None
    done = mbsflow.Results.open(out)
    assert not done.live and len(done.t) >= first


def test_the_keywords_are_the_declared_settings_each_checked_as_declared(chain):
    import inspect
    declared = [k for k, _, _ in mbsflow._core._run_settings()]
    params = inspect.signature(mbsflow.run).parameters
    assert set(params) == set(declared) | {"model", "output", "progress"}
    assert params["threads"].default == 0 and params["coupling"].default == "tight" and params["step"].default is None
    assert "macro_step" in mbsflow.run.__doc__
    m = mbsflow.Model.load(str(chain))
    with pytest.raises(mbsflow.InputError, match=r"extrapolation=3: must be <= 2"):
        mbsflow.run(m, extrapolation=3)
    with pytest.raises(mbsflow.InputError, match=r"partition=0: must be >= 1"):
        mbsflow.run(m, partition=0)
    with pytest.raises(mbsflow.InputError, match=r"coupling=losse: unknown coupling \(tight, loose\)"):
        mbsflow.run(m, coupling="losse")
    with pytest.raises(mbsflow.InputError, match=r"threads=1.5: must be an integer"):
        mbsflow.run(m, threads=1.5)
    with pytest.raises(mbsflow.InputError, match=r"submodel_methods=\[rk4, eul\]: unknown method 'eul'"):
        mbsflow.run(m, coupling="loose", submodel_methods=["rk4", "eul"])
    with pytest.raises(TypeError):
        mbsflow.run(m, nonsense=1)
    # None is the default, as if not given
    assert mbsflow.run(m, threads=1, fields=None, submodel_methods=None, step=None).summary["steps"] > 0
    assert mbsflow.run(m, threads=1, submodel_methods=[]).summary["steps"] > 0  # an empty list: none given
