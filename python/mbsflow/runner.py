"""mbsflow.run: a model run as `mbsflow run` runs it."""
import os
import tempfile

from . import _core
from .results import Results

_ALL_FIELDS = "position,orientation,velocity,angular_velocity,energy"


def run(model, t_end=None, method=None, threads=0, partition=None, coupling="tight", output=None, *,
        fields=None, step=None, rtol=None, atol=None, output_interval=None, output_every=None, variant=None,
        linear_solver="auto", jacobian="auto", partitioner="best", macro_step=None, coupling_tol=None,
        overlap=None, extrapolation=1, max_lag=0, exact_lag=False, submodel_methods=None, executor="flow",
        progress=None, assemble=False):
    """Runs `model` (a Model, or the path of a model file) and returns its Results.

    The keywords are those of `mbsflow run` (`--t-end` is `t_end`, and so on) with the same
    defaults, so the same settings give the same numbers, bit for bit:
      method: rk4, dopri5, colloc or tirk (default: the model's);
      threads: 0 for all cores; partition: a number of submodels, a partition file, or
      None for the CLI's choice; coupling: "tight" or "loose" (then macro_step,
      coupling_tol, overlap, extrapolation, max_lag, exact_lag, submodel_methods);
      fields: as --fields ("all" adds joint forces); progress: called as progress(t, steps);
      assemble: move the bodies onto rigid joints their initial positions violate (else
      such a model is refused, naming the joint).
    output: a results file to write (it stays); without it the results are read into
    memory and the temporary file removed. Ctrl-C stops the run after its current step
    (KeyboardInterrupt; a results file keeps what was written). The GIL is released
    while the run goes.
    """
    path = None
    if not isinstance(model, _core.Model):
        path = os.fspath(model)
        model = _core.Model.load(path)
    fields = fields or _ALL_FIELDS
    args = dict(t_end=t_end, step=step, rtol=rtol, atol=atol, output_interval=output_interval,
                output_every=output_every, method=method, variant=variant, linear_solver=linear_solver,
                jacobian=jacobian, threads=threads, partition=os.fspath(partition) if isinstance(partition, os.PathLike)
                else partition, partitioner=partitioner, coupling=coupling, macro_step=macro_step,
                coupling_tol=coupling_tol, overlap=overlap, extrapolation=extrapolation, max_lag=max_lag,
                exact_lag=exact_lag, submodel_methods=list(submodel_methods or []), executor=executor,
                progress=progress, assemble=assemble)
    def run_to(file):
        try:
            return _core._run(model, file, fields, **args)
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
