"""Results of a run as numpy arrays: from a results file (finished or still being written)
or from mbsflow.run."""
import numpy as np

from ._core import ResultsFile, InputError

# Attribute -> dataset of a multibody results file (docs/results.md).
_DATASETS = {
    "position": "/bodies/position",                  # T x N x 3, m
    "orientation": "/bodies/orientation",            # T x N x 4, w x y z, body to world
    "velocity": "/bodies/velocity",                  # T x N x 3, m/s
    "angular_velocity": "/bodies/angular_velocity",  # T x N x 3, rad/s, world frame
    "body_energy": "/bodies/energy",                 # T x N x 2: kinetic, gravity (J)
    "energy": "/energy",                             # T x 3: kinetic, gravity, elastic (J)
    "joint_wrench": "/joints/force",                 # T x J x 6: force (N), torque (N m), world frame
    "motor_effort": "/joints/motor_effort",          # T x J x 1
    "attachment": "/joints/attachment",              # T x J x 6: the two attachment points, m
    "modal_coordinates": "/flexible/modal_coordinates",  # T x E: flexible bodies' modes, m kg^0.5
}


class Results:
    """A run's results. Arrays are read when first asked for and kept; `refresh()` reads a
    live file again. Attributes: t, body_names, joint_names, position, orientation,
    velocity, angular_velocity, body_energy, energy, joint_force, joint_torque,
    motor_effort, attachment, modal_coordinates (flexible bodies); an ODE run's: t, y
    (points x kept components)."""

    def __init__(self, file=None, arrays=None, summary=None):
        self._file = file
        self._arrays = dict(arrays or {})
        self.summary = summary or {}
        if file is not None:
            self.path = file.path
        else:
            self.path = None

    @classmethod
    def open(cls, path):
        """Opens a results file of `mbsflow run`, `mbsflow ode` or `mbsflow.run(..., output=)`,
        also while a run still writes it (see `live`)."""
        return cls(ResultsFile(str(path)))

    @property
    def live(self):
        """True while a run writes the file (opened as an HDF5 SWMR reader)."""
        return self._file is not None and self._file.live

    @property
    def ode(self):
        return self._file is not None and self._file.ode

    def refresh(self):
        """Reads the file again (a live run's new snapshots)."""
        if self._file is None:
            return self
        path = self._file.path
        # Closed first: opened again while open, HDF5 would hand out the open file, still
        # as the live file it was (a run that ended since is read as finished only anew).
        self._file = None
        self._file = ResultsFile(path)
        self._arrays.clear()
        return self

    def datasets(self):
        """The datasets this run has, by attribute name."""
        if self.ode:
            return ["t", "y"]
        return ["t"] + [a for a, d in _DATASETS.items() if self._has(d)]

    def _has(self, dataset):
        if self._file is None:
            return any(k == dataset for k in self._arrays)
        return self._file.has(dataset)

    def read(self, dataset):
        """Any float64 dataset of the file by its path ("/bodies/position"), in its shape."""
        if dataset not in self._arrays:
            if self._file is None:
                raise InputError("these results have no " + dataset)
            self._arrays[dataset] = self._file.read(dataset)
        return self._arrays[dataset]

    @property
    def t(self):
        if "t" not in self._arrays:
            self._arrays["t"] = self._file.time()
        return self._arrays["t"]

    @property
    def y(self):
        """An ODE run's solution: points x kept components."""
        return self.read("/solution/values")

    @property
    def body_names(self):
        if "body_names" not in self._arrays:
            self._arrays["body_names"] = list(self._file.body_names)
        return self._arrays["body_names"]

    @property
    def joint_names(self):
        if "joint_names" not in self._arrays:
            self._arrays["joint_names"] = list(self._file.joint_names)
        return self._arrays["joint_names"]

    def body(self, name):
        """One body's series as a dict of arrays (T x k each), by name or index."""
        i = name if isinstance(name, int) else self.body_names.index(name)
        fields = ("position", "orientation", "velocity", "angular_velocity", "body_energy")
        return {a: getattr(self, a)[:, i] for a in fields if self._has(_DATASETS[a])}

    def export_csv(self, directory, bodies=()):
        """CSV files as `mbsflow export` writes them; returns their paths."""
        if self._file is None:
            raise InputError("export_csv: these results have no file (run with output=PATH)")
        return self._file.export_csv(str(directory), list(bodies))

    @property
    def joint_force(self):
        """T x J x 3, N: what each joint applies (see docs/results.md for the sign), world frame."""
        return self.joint_wrench[:, :, :3]

    @property
    def joint_torque(self):
        """T x J x 3, N m."""
        return self.joint_wrench[:, :, 3:]

    def load_all(self):
        """Reads every dataset now (the file may then go)."""
        self.t, self.body_names, self.joint_names  # noqa: B018 (reads them)
        for dataset in _DATASETS.values():
            if self._has(dataset):
                self.read(dataset)
        return self

    def detach(self):
        """Everything in memory, the file closed."""
        self.load_all()
        self._file = None
        self.path = None
        return self

    def __repr__(self):
        where = self.path or "memory"
        return f"<mbsflow.Results {where}: {len(self.t)} snapshots>"


def _dataset_property(name, dataset):
    def get(self):
        if not self._has(dataset):
            raise InputError(f"these results have no {dataset} (run with fields= that include it, or 'all')")
        return self.read(dataset)
    get.__doc__ = f"{dataset} as a numpy array"
    return property(get)


for _name, _dataset in _DATASETS.items():
    setattr(Results, _name, _dataset_property(_name, _dataset))
