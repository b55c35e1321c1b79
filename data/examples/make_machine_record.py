"""Writes data/examples/machine_record.wav: a SYNTHETIC acceleration record (not a
measurement) standing in for a measured one in the book's "Model your own harvester" chapter.

It imitates the vibration of a machine that rotates at about 39.5 Hz: its first three
harmonics, whose amplitudes drift slowly, over broadband noise. Standard library only, a fixed
seed, so the file is the same on every run:

    python3 data/examples/make_machine_record.py

16-bit mono WAV at 2 kHz, 6 s; full scale (sample 32767) stands for 20 m/s^2, so run it with
`endstop random --accel-file data/examples/machine_record.wav --accel-scale 20`.
"""

import math
import random
import struct
import wave
from pathlib import Path

RATE_HZ = 2000
DURATION_S = 6.0
FULL_SCALE_M_PER_S2 = 20.0
ROTATION_HZ = 39.5
# (harmonic, amplitude in m/s^2): the third harmonic lies near the cantilever's resonance.
HARMONICS = [(1, 2.0), (2, 1.0), (3, 4.0)]
NOISE_RMS_M_PER_S2 = 1.5


def main() -> None:
    rng = random.Random(2012)
    n = int(RATE_HZ * DURATION_S)
    frames = bytearray()
    for k in range(n):
        t = k / RATE_HZ
        drift = 1.0 + 0.2 * math.sin(2.0 * math.pi * 0.3 * t)
        a = sum(
            amp * drift * math.sin(2.0 * math.pi * h * ROTATION_HZ * t + h)
            for h, amp in HARMONICS
        )
        a += rng.gauss(0.0, NOISE_RMS_M_PER_S2)
        sample = max(-32767, min(32767, round(a / FULL_SCALE_M_PER_S2 * 32767)))
        frames += struct.pack("<h", sample)
    out = Path(__file__).with_name("machine_record.wav")
    with wave.open(str(out), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(RATE_HZ)
        w.writeframes(bytes(frames))


if __name__ == "__main__":
    main()
