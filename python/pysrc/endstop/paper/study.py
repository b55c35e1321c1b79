"""Why the paper deviates (the library's ``endstop::paper::study``) in pieces a cluster can
schedule. ``just deviations`` runs the same pieces in one process; here each is a function whose
arguments and result pickle, so a Dask client can map them over workers:

* :func:`design`: the Saltelli design (unit-cube points, one row each) over :func:`factors`;
* :func:`evaluate`: the claim quantities of a prototype at one point (the ensemble claims of
  Figures 12, 14 and 15 too, when ``ensemble_records`` is given);
* :func:`indices`: the Sobol indices from the evaluations of every design point, with the
  columns of the study's ``sobol.parquet``;
* :func:`calibration_starts`, :func:`calibrate_start`, :func:`calibration`: the multi-claim
  calibration, one task per start, then the best set beside the published one.

A prototype is ``"p1"`` or ``"p2"``; its base is the published device and its ranges those of
``data/sensitivity.toml``. ``python/examples/study_dask.py`` runs the whole study on a Dask
cluster.
"""

from .. import _native

SEED = 13
"""The scramble of the study's design and of its calibration's Sobol starts (``just deviations``'s)."""


def factors():
    """The uncertain factors' keys, in the order of a point's coordinates."""
    return _native.paper_study_factors()


def design(base_rows, seed=SEED):
    """The Saltelli design of ``base_rows`` base rows (a power of two): a numpy array of
    ``base_rows * (len(factors()) + 2)`` points in unit-cube coordinates."""
    return _native.paper_study_design(int(base_rows), int(seed))


def evaluate(prototype, point, ensemble_records=None):
    """The study's quantities of ``prototype`` at ``point`` (unit cube): a list of dicts
    (``claim``, ``quantity``, the claim's ``paper`` value, ``tolerance`` and ``unit``,
    ``outcome``, ``value``, ``deviation``, ``meets``, ``kind``).
    With ``ensemble_records`` (records per level; the figures use 32) the ensemble claims of
    Figures 12, 14 and 15 are evaluated too, at a cost of tens of 10 s records."""
    records = None if ensemble_records is None else int(ensemble_records)
    return _native.paper_study_evaluate(prototype, [float(u) for u in point], records)


def indices(prototype, base_rows, evaluations, ensemble_records=None, seed=SEED):
    """Sobol first-order and total indices with 95 % bootstrap intervals from
    ``evaluations`` (one :func:`evaluate` result per point of ``design(base_rows, seed)``, in
    design order, in the same scope): one dict per quantity and factor (``prototype``,
    ``claim``, ``quantity``, ``factor``, ``first``, ``first_lo``, ``first_hi``, ``total``,
    ``total_lo``, ``total_hi``, and the shares of points where the quantity is absent)."""
    records = None if ensemble_records is None else int(ensemble_records)
    return _native.paper_study_indices(prototype, int(base_rows), evaluations, records, int(seed))


def calibration_starts(prototype, starts, seed=SEED):
    """The calibration's starts: the published point, then ``starts`` Sobol points (rows)."""
    return _native.paper_study_calibration_starts(prototype, int(starts), int(seed))


def calibrate_start(prototype, start, starts, iterations, ensemble_records=None, seed=SEED):
    """The Nelder-Mead search of the worst normalised deviation from start ``start`` of
    ``calibration_starts(prototype, starts, seed)``, at most ``iterations`` iterations: a dict
    (``start``, ``point``, ``deviations``, ``worst``, ``iterations``, ``failures``)."""
    records = None if ensemble_records is None else int(ensemble_records)
    return _native.paper_study_calibrate_start(prototype, int(start), int(starts),
                                               int(iterations), records, int(seed))


def calibration(prototype, fits, ensemble_records=None):
    """The calibration from its starts' fits (:func:`calibrate_start` results, any order):
    ``fits`` best first, ``worst`` and ``published_worst`` (worst |normalised deviation| of
    the best and the published set), ``meets_all``, and the evaluations ``best`` and
    ``published``."""
    records = None if ensemble_records is None else int(ensemble_records)
    return _native.paper_study_calibration(prototype, list(fits), records)


__all__ = ["SEED", "factors", "design", "evaluate", "indices", "calibration_starts",
           "calibrate_start", "calibration"]
