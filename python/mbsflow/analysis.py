"""Small motions about a working point: the linearised model, its natural modes and its
frequency response (docs/modes.md). The model is linearised at its static equilibrium
(at="equilibrium", the default) or at its initial state (at="initial")."""
from dataclasses import dataclass

import numpy as np
import scipy.sparse

from . import _core


def _load(model):
    return model if isinstance(model, _core.Model) else _core.Model.load(model)


def _csc(parts):
    data, indices, indptr, shape = parts
    return scipy.sparse.csc_matrix((data, indices, indptr), shape=shape)


@dataclass
class LinearModel:
    """M x'' + D x' + K x = f with C x = 0; x holds 6 coordinates per free body (translation,
    then rotation as a world-frame rotation vector), in the order of `bodies`, from
    start[k] (a flexible body's frame has its modal coordinates after its 6; its node bodies
    have none)."""
    M: scipy.sparse.csc_matrix
    D: scipy.sparse.csc_matrix
    K: scipy.sparse.csc_matrix
    C: scipy.sparse.csc_matrix
    bodies: list
    state: np.ndarray
    start: list


@dataclass
class Modes:
    """The lowest modes, ascending: frequency (Hz), damping_ratio, eigenvalue (complex,
    1/s), rigid_body, residual; shape (modes x bodies x 6, complex, mass-normalised, world
    frame); kinetic_share and strain_share (modes x bodies)."""
    frequency: np.ndarray
    damping_ratio: np.ndarray
    eigenvalue: np.ndarray
    rigid_body: np.ndarray
    residual: np.ndarray
    shape: np.ndarray
    kinetic_share: np.ndarray
    strain_share: np.ndarray
    solver: str
    state: np.ndarray


def linearize(model, at="equilibrium"):
    """The model (a Model or a model file) linearised: M, D, K, C as scipy sparse matrices."""
    d = _core._linearize(_load(model), at)
    return LinearModel(_csc(d["M"]), _csc(d["D"]), _csc(d["K"]), _csc(d["C"]), list(d["bodies"]), d["state"],
                       list(d["start"]))


def modes(model, n=10, at="equilibrium", damped=True, solver="auto"):
    """The n lowest modes (damped complex ones, or of M and K with damped=False)."""
    d = _core._modes(_load(model), n, at, damped, solver)
    return Modes(np.asarray(d["frequency"]), np.asarray(d["damping_ratio"]), np.asarray(d["eigenvalue"]),
                 np.asarray(d["rigid_body"]), np.asarray(d["residual"]), d["shape"], d["kinetic_share"],
                 d["strain_share"], d["solver"], d["state"])


def frf(model, inputs, outputs, frequencies, at="equilibrium"):
    """H (frequencies x outputs x inputs, complex): the steady response per unit harmonic
    input. inputs: "BODY:fx" ... "BODY:tz"; outputs: "BODY:x" ... "BODY:rz", "vx".. for
    velocity, "ax".. for acceleration; frequencies in Hz."""
    inputs = [inputs] if isinstance(inputs, str) else list(inputs)
    outputs = [outputs] if isinstance(outputs, str) else list(outputs)
    return _core._frf(_load(model), inputs, outputs, [float(f) for f in frequencies], at)
