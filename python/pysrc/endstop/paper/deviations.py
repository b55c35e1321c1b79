"""Why the paper deviates (the library's ``endstop::paper::deviations``) in pieces a cluster can
schedule. ``just deviations`` runs the same pieces in one process; here each is a function whose
arguments and result pickle, so a Dask client can map them over workers:

* :func:`design`: the Saltelli design (unit-cube points, one row each) over :func:`factors`;
* :func:`evaluate`: the claim quantities of a prototype at one point (the ensemble claims of
  Figures 12, 14 and 15 too, when ``ensemble_records`` is given);
* :func:`indices`: the Sobol indices from the evaluations of every design point, with the
  columns of the study's ``sobol.parquet``;
* :func:`calibration_starts`, :func:`calibrate_start`, :func:`calibration`: the multi-claim
  calibration, one task per start, then the best set beside the published one;
* :func:`history`: the history match in waves, replayed from the waves so far: the next
  wave's design (whose points are then evaluated anywhere), each wave's summary, the answer.

A prototype is ``"p1"`` or ``"p2"``; its base is the published device and its ranges those of
``data/sensitivity.toml``. ``python/examples/study_dask.py`` runs the whole study on a Dask
cluster.
"""

from .. import _native

SEED = 13
"""The scramble of the study's design and of its calibration's Sobol starts (``just deviations``'s)."""


def factors():
    """The uncertain factors' keys, in the order of a point's coordinates."""
    return _native.paper_deviations_factors()


def design(base_rows, seed=SEED):
    """The Saltelli design of ``base_rows`` base rows (a power of two): a numpy array of
    ``base_rows * (len(factors()) + 2)`` points in unit-cube coordinates."""
    return _native.paper_deviations_design(int(base_rows), int(seed))


def evaluate(prototype, point, ensemble_records=None):
    """The study's quantities of ``prototype`` at ``point`` (unit cube): a list of dicts
    (``claim``, ``quantity``, the claim's ``paper`` value, ``tolerance`` and ``unit``,
    ``outcome``, ``value``, ``deviation``, ``meets``, ``kind``).
    With ``ensemble_records`` (records per level; the figures use 32) the ensemble claims of
    Figures 12, 14 and 15 are evaluated too, at a cost of tens of 10 s records."""
    records = None if ensemble_records is None else int(ensemble_records)
    return _native.paper_deviations_evaluate(prototype, [float(u) for u in point], records)


def indices(prototype, base_rows, evaluations, ensemble_records=None, seed=SEED):
    """Sobol first-order and total indices with 95 % bootstrap intervals from
    ``evaluations`` (one :func:`evaluate` result per point of ``design(base_rows, seed)``, in
    design order, in the same scope): one dict per quantity and factor (``prototype``,
    ``claim``, ``quantity``, ``factor``, ``first``, ``first_lo``, ``first_hi``, ``total``,
    ``total_lo``, ``total_hi``, and the shares of points where the quantity is absent)."""
    records = None if ensemble_records is None else int(ensemble_records)
    return _native.paper_deviations_indices(prototype, int(base_rows), evaluations, records, int(seed))


def calibration_starts(prototype, starts, seed=SEED):
    """The calibration's starts: the published point, then ``starts`` Sobol points (rows)."""
    return _native.paper_deviations_calibration_starts(prototype, int(starts), int(seed))


def calibrate_start(prototype, start, starts, iterations, ensemble_records=None, seed=SEED):
    """The Nelder-Mead search of the worst normalised deviation from start ``start`` of
    ``calibration_starts(prototype, starts, seed)``, at most ``iterations`` iterations: a dict
    (``start``, ``point``, ``deviations``, ``worst``, ``iterations``, ``failures``)."""
    records = None if ensemble_records is None else int(ensemble_records)
    return _native.paper_deviations_calibrate_start(prototype, int(start), int(starts),
                                               int(iterations), records, int(seed))


def calibration(prototype, fits, ensemble_records=None):
    """The calibration from its starts' fits (:func:`calibrate_start` results, any order):
    ``fits`` best first, ``worst`` and ``published_worst`` (worst |normalised deviation| of
    the best and the published set), ``meets_all``, and the evaluations ``best`` and
    ``published``."""
    records = None if ensemble_records is None else int(ensemble_records)
    return _native.paper_deviations_calibration(prototype, list(fits), records)


def history(prototype, waves, per_input=10, max_waves=4, pool=1 << 14, ensemble_records=None,
            seed=SEED, sobol=False):
    """The history match of ``prototype`` from its waves so far. ``waves`` is a list of
    ``(points, evaluations)``: each wave's design as the previous call returned it in
    ``next_design`` and the :func:`evaluate` results at its points, in order (start with
    ``[]``). The emulators are refitted from the runs at every call (deterministic: the same
    waves give the same match), so only the runs need to travel.

    Returns a dict: ``next_design`` (an array of points, or None once the match has ended:
    the space emptied, stopped shrinking, or ``max_waves`` ran), ``outputs`` (the emulated
    claims), ``waves`` (per wave: the non-implausible share of the cube, the share with every
    claim within the cut, each claim's share ruled out and its emulator's leave-one-out
    standardised errors, the yes/no claims met at its runs, why it ended), ``answer``,
    ``projections`` (the last wave's 2-D projections, one dict per cell) and, with
    ``sobol=True``, ``indices`` (the first wave's emulators' Sobol indices with the 95 %
    interval of their posterior draws)."""
    records = None if ensemble_records is None else int(ensemble_records)
    ws = [([[float(u) for u in p] for p in points], [list(e) for e in evals])
          for points, evals in waves]
    return _native.paper_deviations_history(prototype, ws, int(per_input), int(max_waves), int(pool),
                                       records, int(seed), bool(sobol))


__all__ = ["SEED", "factors", "design", "evaluate", "indices", "calibration_starts",
           "calibrate_start", "calibration", "history"]
