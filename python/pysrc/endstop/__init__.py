"""The Le & Halvorsen (2012) MEMS electrostatic energy harvester with end-stops.

The model runs in Rust (the repository's `endstop` library); this package is its Python face:

* :class:`Device`: the parameters of a device file, validated (``Device.from_toml(path)``,
  ``Device.from_dict(d)``, ``Device.prototype(1 | 2)``); a bad value raises
  :class:`ParamError` naming the field and its valid range;
* :mod:`endstop.linear`: linear theory (eqs 11-22): two-port, k^2, Qm readings, eq 21, the
  linear output PSD;
* :mod:`endstop.study`: simulations (frequency up-sweeps, amplitude sweeps, one random record,
  an ensemble, the charging of a storage) of any device, with or without an interface circuit,
  returning dicts of numbers and numpy arrays;
* :func:`endstop.design`: the designer's inverse question, the most DC power over ranges of a
  device's parameters and a choice of interface circuits within limits on impacts and stroke,
  under a sine, band-limited white noise or a measured acceleration record (the ``endstop
  design`` command's);
* :mod:`endstop.fit`: fitting a device's parameters to measured sweeps, with uncertainty;
* :mod:`endstop.paper`: the paper's figure protocols (``endstop.paper.fig13.run()``) and the
  study of why the paper deviates (:mod:`endstop.paper.deviations`, ready for a Dask cluster).

Every simulation releases the GIL while it runs.
"""

from ._native import Device, ParamError, SolverError, __version__
from . import fit, linear, paper, spectrum, springs, study
from ._design import design

__all__ = ["Device", "ParamError", "SolverError", "design", "fit", "linear", "paper", "spectrum", "springs", "study", "__version__"]
