"""Fitting a device to a measured output spectrum under random vibration, the twin of
``endstop fit --spectrum PSD.csv:S[:N]``.

Each evaluation of the model is an ensemble of 10 s records, so the fit runs on Gaussian-process
emulators of three features of the spectrum (the logarithm of the band power, its centroid and
its spread) over the free parameters, built from a design of ensembles (``per_param`` points per
parameter, ``design_records`` records each). The posterior of the parameters (flat prior on
their ranges) carries the emulators' uncertainty and the measured spectrum's sampling variance
(``records``: how many 10 s records the measured PSD averages). The method is the library's
``endstop::fit::spectrum``, described in the book chapter "Fit your measurements".
"""

from . import _native


def fit(device, freq_hz, psd_w_per_hz, accel_psd_g2_per_hz, free, records=1, per_param=10,
        design_records=16, seed=17):
    """Fits ``free`` (a dict ``{path: (lo, hi)}``; ``"drive.accel_scale"`` is a factor on the
    stated acceleration) of ``device`` to the measured output power PSD of both loads
    ``psd_w_per_hz`` (W/Hz) at ``freq_hz`` (Hz, increasing), driven at the stated two-sided
    acceleration PSD ``accel_psd_g2_per_hz`` (g²/Hz).

    Returns a dict: ``params`` (per parameter: ``path``, posterior ``mean``, maximum-posterior
    ``best``, 95 % ``interval``), ``features``, ``measured``, ``predicted`` (emulated at the
    best point), ``implausibility`` (per feature; above 3 the model does not reach the
    measurement inside the ranges) and ``effective_samples``. Bad data raise ``ValueError``; a
    bad path or range :class:`endstop.ParamError`."""
    return _native.fit_spectrum(device, [float(f) for f in freq_hz],
                                [float(s) for s in psd_w_per_hz], float(accel_psd_g2_per_hz),
                                [(p, float(lo), float(hi)) for p, (lo, hi) in free.items()],
                                int(records), int(per_param), int(design_records), int(seed))


__all__ = ["fit"]
