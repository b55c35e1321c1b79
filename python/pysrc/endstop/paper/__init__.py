"""The paper's figure protocols, as the book's chapters run them (the library's
``endstop::paper``): ``endstop.paper.fig09.run()``, ``endstop.paper.fig13.run()``, the
calibration of prototype 1 (``endstop.paper.fig09.calibrate()``), and the study of why the
paper deviates, in pieces a cluster can schedule (:mod:`endstop.paper.deviations`). The other
figures are not exposed yet; each will be a module ``figNN`` with a ``run`` returning
``numbers`` (the keys of its ``summary.json``) and ``claims``."""

from . import deviations, fig09, fig13

__all__ = ["deviations", "fig09", "fig13"]
