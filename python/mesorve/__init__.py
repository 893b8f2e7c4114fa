"""mesorve: a mesoscale RVE of concrete (matrix, aggregates, cohesive-contact ITZ) as a
material law for FE² from Python.

    >>> import numpy as np, mesorve
    >>> model = mesorve.Model()                 # the paper's RVE (embedded); or a scene path
    >>> points = model.points(4, threads=2)
    >>> sig, D = points.update(np.full((4, 3), 1e-5) * [1, 0, 0])   # trial
    >>> points.commit()                         # the host's increment converged

See docs/python.md in the repository.
"""

from ._mesorve import VERSION, Model, Points, RveError

__all__ = ["Model", "Points", "RveError", "VERSION"]
__version__ = VERSION
