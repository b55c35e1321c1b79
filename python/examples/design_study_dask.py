"""A design study distributed with Dask: prototype 2 at 10 V over a grid of end-stop gaps x_max
and end-stop dampings b_im. Each point gets

* the up-jump frequency of an up-sweep at 0.31 g rms (Figure 13's protocol: 600-850 Hz in 2 Hz
  steps, jump refined to 0.1 Hz), with the impact onset and the branch end;
* the broadband efficiency 2P/(m Sa) of one random record at Sa = 1.69e-3 g^2/Hz (a level of
  Figure 14 where the mass strikes the stops), beside eq 21's linear value;
* the seconds the point took on its worker.

The points are independent tasks (`client.map`); every result goes into one Parquet file.

    pip install "./python[dask]"
    python python/examples/design_study_dask.py --gaps 6e-6,8e-6,10e-6 --bims 0.2,0.4 \
        --out design.parquet                       # a LocalCluster on this machine
    python python/examples/design_study_dask.py --scheduler tcp://host:8786 ...   # a cluster

On a Slurm cluster, start the workers with dask-jobqueue (see the repository README) and pass
the scheduler's address, or use `--slurm-jobs N` to let this script create a SLURMCluster.
"""

import argparse
import time

import numpy as np
import pandas as pd

PSD_G2_PER_HZ = 1.69e-3
ACCEL_RMS_G = 0.31
BIAS_V = 10.0


def design_point(device_toml, gap_m, bim, duration_s, seed):
    """One point of the grid (runs on a worker; the device travels as TOML text)."""
    import endstop

    t0 = time.perf_counter()
    base = endstop.Device.from_toml_str(device_toml, "prototype2.toml")
    dev = base.with_bias(BIAS_V).with_endstop("linear", bim).with_endstop_gap(gap_m)
    sweep = endstop.study.up_sweep(dev, ACCEL_RMS_G, start_hz=600, stop_hz=850, step_hz=2.0)
    rec = endstop.study.ensemble(dev, PSD_G2_PER_HZ, records=1, duration_s=duration_s, seed=seed)
    return {
        "endstop_gap_m": gap_m,
        "bim_n_s_per_m": bim,
        "onset_hz": sweep["onset_hz"],
        "jump_hz": sweep["jump_hz"],
        "branch_end_hz": sweep["branch_end_hz"],
        "max_v1_rms_v": sweep["max_v1_rms_v"],
        "efficiency": rec["efficiency"],
        "eq21_efficiency": endstop.linear.eq21_efficiency(dev),
        "contact_fraction": rec["contact_fraction"],
        "seconds": time.perf_counter() - t0,
    }


def floats(text):
    return [float(x) for x in text.split(",") if x]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--gaps", type=floats, default=floats("6e-6,8e-6,10e-6"),
                    help="end-stop gaps x_max (m), comma separated (at most x0 = 10e-6)")
    ap.add_argument("--bims", type=floats, default=floats("0.2,0.4,0.8"),
                    help="end-stop dampings b_im (N s/m), comma separated")
    ap.add_argument("--duration-s", type=float, default=10.0,
                    help="length of the random record of each point (s)")
    ap.add_argument("--seed", type=int, default=2012)
    ap.add_argument("--out", default="design_study.parquet")
    ap.add_argument("--workers", type=int, default=2, help="LocalCluster workers")
    ap.add_argument("--scheduler", help="address of a running Dask scheduler")
    ap.add_argument("--slurm-jobs", type=int, help="workers to start as Slurm jobs")
    a = ap.parse_args()

    from dask.distributed import Client, LocalCluster

    import endstop

    if a.scheduler:
        client = Client(a.scheduler)
    elif a.slurm_jobs:
        from dask_jobqueue import SLURMCluster

        cluster = SLURMCluster(cores=1, processes=1, memory="2GB", walltime="01:00:00")
        cluster.scale(jobs=a.slurm_jobs)
        client = Client(cluster)
    else:
        cluster = LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    client.wait_for_workers(1)
    workers = len(client.scheduler_info()["workers"])
    device_toml = endstop.Device.prototype(2).to_toml()
    grid = [(g, b) for g in a.gaps for b in a.bims]
    t0 = time.perf_counter()
    futures = client.map(design_point, [device_toml] * len(grid), [g for g, _ in grid],
                         [b for _, b in grid], [a.duration_s] * len(grid), [a.seed] * len(grid),
                         pure=False)
    rows = client.gather(futures)
    wall = time.perf_counter() - t0
    df = pd.DataFrame(rows).sort_values(["endstop_gap_m", "bim_n_s_per_m"])
    df.to_parquet(a.out, index=False)
    client.close()
    per_point = np.array(df["seconds"])
    print(df.to_string(index=False))
    print(f"{len(df)} points on {workers} workers in {wall:.1f} s wall; per point {per_point.mean():.2f} s "
          f"(min {per_point.min():.2f}, max {per_point.max():.2f}) of worker time")
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
