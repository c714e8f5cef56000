"""mbsflow.Simulation: a model stepped from Python, a controller in the loop."""
import inspect
import os

from . import _core

# Its keywords are the run settings declared for it (mbsflow/runtime/run_settings.hpp), with
# mbsflow.run's names, defaults and checks.
_SETTINGS = _core._run_settings("simulation")
# After the model, in the order they always had.
_POSITIONAL = ("method", "step", "rtol", "atol", "t_end", "variant", "threads", "linear_solver", "jacobian")
# A controller steps small models between its own calls: one thread unless asked.
_DEFAULTS_HERE = {"threads": 1}


def _signature():
    P = inspect.Parameter
    defaults = {keyword: _DEFAULTS_HERE.get(keyword, default) for keyword, default, _ in _SETTINGS}
    params = [P("self", P.POSITIONAL_OR_KEYWORD), P("model", P.POSITIONAL_OR_KEYWORD)]
    params += [P(k, P.POSITIONAL_OR_KEYWORD, default=defaults[k]) for k in _POSITIONAL]
    params += [P(k, P.KEYWORD_ONLY, default=defaults[k]) for k, _, _ in _SETTINGS if k not in _POSITIONAL]
    return inspect.Signature(params)


_SIGNATURE = _signature()


class Simulation(_core.Simulation):
    def __init__(self, *args, **kwargs):
        bound = _SIGNATURE.bind(self, *args, **kwargs)  # TypeError for a keyword that is no setting of it
        settings = dict(bound.arguments)
        del settings["self"]
        model = settings.pop("model")
        if not isinstance(model, _core.Model):
            model = _core.Model.load(os.fspath(model))
        for keyword, default in _DEFAULTS_HERE.items():
            if settings.get(keyword) is None:
                settings[keyword] = default
        super().__init__(model, settings)


Simulation.__init__.__signature__ = _SIGNATURE
Simulation.__doc__ = """A model (a Model, or the path of a model file) stepped from Python.

step() takes one step of the method (False once at t_end), step(dt) and advance_to(t) land
on a time exactly; between steps the state is read through read-only numpy views
(positions, velocities, orientations, angular_velocities, state) and loads are set with
set_load(). Left alone, `while sim.step(): pass` takes the steps of mbsflow.run with the
same settings and ends on the same state to the bit. See docs/python.md.

Settings (None: the model's, or chosen for it), as mbsflow.run's:
""" + "\n".join(f"  {keyword} = {_DEFAULTS_HERE.get(keyword, default)!r}: {help}" for keyword, default, help in _SETTINGS)
