"""mbsflow.run: a model run as `mbsflow run` runs it."""
import inspect
import os
import tempfile

from . import _core
from .results import Results

# The settings are declared once, in C++ (mbsflow/runtime/run_settings.hpp): their keywords,
# defaults and help make run's signature and docstring here.
_SETTINGS = _core._run_settings()
_POSITIONAL = ("t_end", "method", "threads", "partition", "coupling")  # after the model, in this order


def _signature():
    P = inspect.Parameter
    defaults = {keyword: default for keyword, default, _ in _SETTINGS}
    params = [P("model", P.POSITIONAL_OR_KEYWORD)]
    params += [P(k, P.POSITIONAL_OR_KEYWORD, default=defaults[k]) for k in _POSITIONAL]
    params.append(P("output", P.POSITIONAL_OR_KEYWORD, default=None))
    params += [P(k, P.KEYWORD_ONLY, default=d) for k, d, _ in _SETTINGS if k not in _POSITIONAL]
    params.append(P("progress", P.KEYWORD_ONLY, default=None))
    return inspect.Signature(params)


_SIGNATURE = _signature()


def run(*args, **kwargs):
    bound = _SIGNATURE.bind(*args, **kwargs)  # TypeError for a keyword that is no setting
    settings = dict(bound.arguments)
    model = settings.pop("model")
    output = settings.pop("output", None)
    progress = settings.pop("progress", None)
    path = None
    if not isinstance(model, _core.Model):
        path = os.fspath(model)
        model = _core.Model.load(path)

    def run_to(file):
        try:
            return _core._run(model, file, settings, progress)
        except _core.ModelError as e:  # named with the model's file, as the CLI does
            if path is None:
                raise
            raise _core.ModelError(f"{path}: {e}") from None

    if output is not None:
        if os.fspath(output) == "":
            raise _core.InputError("output: give a file name (an empty one writes nothing)")
        summary = run_to(os.fspath(output))
        results = Results.open(output)
        results.summary = summary
        return results
    with tempfile.TemporaryDirectory(prefix="mbsflow-") as folder:
        summary = run_to(os.path.join(folder, "results.h5"))
        results = Results.open(os.path.join(folder, "results.h5")).detach()
    results.summary = summary
    return results


run.__signature__ = _SIGNATURE
run.__doc__ = """Runs `model` (a Model, or the path of a model file) and returns its Results.

The settings are those of `mbsflow run` (`--t-end` is `t_end`, and so on) with the same
defaults, so the same settings give the same numbers, bit for bit. output: a results file
to write (it stays); without it the results are read into memory and the temporary file
removed. progress: called as progress(t, steps). Ctrl-C stops the run after its current
step (KeyboardInterrupt; a results file keeps what was written). The GIL is released while
the run goes.

Settings (None: the model's, or chosen for it):
""" + "\n".join(f"  {keyword} = {default!r}: {help}" for keyword, default, help in _SETTINGS)
