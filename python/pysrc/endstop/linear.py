"""Linear theory of the differential mode (eqs 11-22 of the paper), and of any device.

The two-port functions need a capacitor-pair transducer (another device raises
``ValueError``); :func:`output_psd` and :func:`white_noise_power_w` take any device.

* :func:`two_port`: C, Gamma, K, k^2, the open-circuit resonance, r_L (eq 22), the three Qm
  readings and the eq 21 efficiency, as a dict;
* :func:`k2`, :func:`qm`, :func:`eq21_efficiency`, :func:`eq21_power_w`;
* :func:`output_psd`: the linearised model's output power PSD of both loads (W/Hz);
* :func:`bias_for_coupling`: the bias giving a coupling k^2 (eq 18 inverted);
* :func:`white_noise_power_w`: the linearised model's power under band-limited white noise.
"""

import numpy as np

from . import _native

two_port = _native.two_port
k2 = _native.k2
qm = _native.qm
eq21_efficiency = _native.eq21_efficiency
eq21_power_w = _native.eq21_power_w
bias_for_coupling = _native.bias_for_coupling


def white_noise_power_w(device, psd_g2_per_hz, lo_hz, hi_hz):
    """Mean power of the loads (W) of the linearised ``device`` under white base acceleration
    of two-sided density ``psd_g2_per_hz`` (g^2/Hz) limited to ``[lo_hz, hi_hz]`` (Hz)."""
    return _native.white_noise_power_w(device, float(psd_g2_per_hz), float(lo_hz),
                                       float(hi_hz))


def output_psd(device, psd_g2_per_hz, freq_hz):
    """One-sided output power PSD of both loads (W/Hz) of the linearised model at the
    frequencies ``freq_hz`` (Hz), for a two-sided acceleration PSD ``psd_g2_per_hz`` (g^2/Hz)."""
    f = np.ascontiguousarray(freq_hz, dtype=np.float64)
    return _native.linear_output_psd(device, float(psd_g2_per_hz), f)


__all__ = ["two_port", "k2", "qm", "eq21_efficiency", "eq21_power_w", "output_psd",
           "bias_for_coupling", "white_noise_power_w"]
