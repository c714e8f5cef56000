"""mbsflow: multibody dynamics and large ODE systems, in parallel.

    import mbsflow
    model = mbsflow.generate.chain(n=100, t_end=2.0)
    results = mbsflow.run(model, method="dopri5")
    results.position[-1]            # numpy (bodies x 3), the last snapshot

Models (`Model.load`, `Model.from_dict`, `generate`), runs (`run`, `Results.open`),
stepping with a controller in the loop (`Simulation`), and scipy's `solve_ivp` shape on
mbsflow's methods (`solve_ivp`). Errors are `mbsflow.Error`: `InputError` (also a
ValueError) and `RunError` (also a RuntimeError). See docs/python.md.
"""
from ._core import Error, InputError, ModelError, RunError, Model, generate, __version__
from .simulation import Simulation
from .results import Results
from .runner import run
from .ivp import solve_ivp, OdeResult, OdeSolution, CompiledRhs
from .analysis import linearize, modes, frf, LinearModel, Modes

__all__ = ["linearize", "modes", "frf", "LinearModel", "Modes", "Error", "InputError", "ModelError", "RunError", "Model", "Simulation", "generate", "Results", "run",
           "solve_ivp", "OdeResult", "OdeSolution", "CompiledRhs", "__version__"]
