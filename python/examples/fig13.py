"""Figure 13 from Python: prototype 2 at 10 V, up-sweeps at 0.12 and 0.31 g rms with the linear
and the Hertz end-stop laws (published parameters), drawn with matplotlib.

    pip install "./python[examples]"
    python python/examples/fig13.py [--out fig13.png]
"""

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import endstop  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="fig13.png", help="image to write (PNG, SVG or PDF)")
    a = ap.parse_args()
    run = endstop.paper.fig13.run()
    fig, ax = plt.subplots(figsize=(8, 5))
    for c in run["curves"]:
        s = c["in_range"]
        style = "--" if c["law"] == "hertz" else "-o"
        ax.plot(s["freq_hz"], s["v1_rms_v"], style, ms=3, label=f"simulation: {c['label']}")
        if c["sweep"]["jump_hz"] is not None:
            ax.axvline(c["sweep"]["jump_hz"], color="grey", lw=0.8, ls=":")
    ax.set_xlim(600, 850)
    ax.set_xlabel("Frequency [Hz]")
    ax.set_ylabel("RMS output voltage V1 [V]")
    ax.set_title("Figure 13: prototype 2, 10 V, up-sweeps (published parameters)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(a.out, dpi=120)
    for key, value in sorted(run["numbers"].items()):
        print(f"{key:40s} {value:.6g}")
    for c in run["claims"]:
        print(f"{c['claim']} {c['quantity']}: {c['ours']:g} ({c['note']})")
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
