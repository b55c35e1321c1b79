"""Why the paper deviates, on a Dask cluster: the Sobol indices and the multi-claim calibration
of ``just study``, with every design point and every calibration start a task of its own.

This is the route for the studies one machine cannot run in the ``just study`` budget, above
all those with the ensemble claims of Figures 12, 14 and 15 (``--ensemble-records``: each point
then simulates tens of 10 s records per level). The pieces are the library's own functions
(:mod:`endstop.paper.study`), so the numbers are those ``just study`` gives for the same
settings.

Writes, under ``--out-dir``:

* ``evaluations.parquet``: every design point (its unit-cube coordinates) and every quantity
  there (outcome, value, normalised deviation, met or not);
* ``sobol.parquet``: the indices, with the columns of the study's own ``sobol.parquet``;
* ``calibration.parquet``: every start's fit, and the best and the published set's
  evaluations.

    pip install "./python[dask]"
    python python/examples/study_dask.py --prototype p2 --base 4 --ensemble-records 32 \
        --out-dir study-p2                          # a LocalCluster on this machine
    python python/examples/study_dask.py --scheduler tcp://host:8786 ...   # a cluster
    python python/examples/study_dask.py --slurm-jobs 64 ...               # Slurm workers

With ``--slurm-jobs N`` the script starts N one-core workers as Slurm jobs (dask-jobqueue);
for any other scheduler start the workers yourself and pass ``--scheduler``.
"""

import argparse
import os
import time

import pandas as pd


def client_for(a):
    from dask.distributed import Client, LocalCluster

    if a.scheduler:
        return Client(a.scheduler)
    if a.slurm_jobs:
        from dask_jobqueue import SLURMCluster

        cluster = SLURMCluster(cores=1, processes=1, memory="4GB", walltime="04:00:00")
        cluster.scale(jobs=a.slurm_jobs)
        return Client(cluster)
    cluster = LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    return Client(cluster)


def progress(futures, what):
    """Report every tenth of the tasks as they finish (a long study needs to show it lives)."""
    from dask.distributed import as_completed

    n, done, t0 = len(futures), 0, time.perf_counter()
    for _ in as_completed(futures):
        done += 1
        if done == n or done % max(1, n // 10) == 0:
            print(f"  {what}: {done}/{n} in {time.perf_counter() - t0:.0f} s", flush=True)


def run(client, a, proto):
    from endstop.paper import study

    factors = study.factors()
    points = study.design(a.base)
    n = len(points)
    print(f"{proto}: {n} design points, {a.starts + 1} calibration starts", flush=True)
    t0 = time.perf_counter()
    futures = client.map(study.evaluate, [proto] * n, list(points), [a.ensemble_records] * n,
                         pure=False)
    progress(futures, "design points")
    evaluations = client.gather(futures)
    sobol_s = time.perf_counter() - t0
    rows = study.indices(proto, a.base, evaluations, a.ensemble_records)

    t0 = time.perf_counter()
    k = a.starts + 1
    futures = client.map(study.calibrate_start, [proto] * k, range(k), [a.starts] * k,
                         [a.iters] * k, [a.ensemble_records] * k, pure=False)
    progress(futures, "calibration starts")
    cal = study.calibration(proto, client.gather(futures), a.ensemble_records)
    cal_s = time.perf_counter() - t0

    evals = [dict(e, prototype=proto, point=i, **dict(zip(factors, map(float, points[i]))))
             for i, es in enumerate(evaluations) for e in es]
    cals = [dict(e, prototype=proto, set=s) for s in ("best", "published") for e in cal[s]]
    fits = [dict(prototype=proto, start=f["start"], worst=f["worst"],
                 iterations=f["iterations"], failures=f["failures"],
                 **dict(zip(factors, f["point"]))) for f in cal["fits"]]
    print(f"{proto}: design {sobol_s:.0f} s, calibration {cal_s:.0f} s wall; worst |deviation| "
          f"{cal['worst']:.3g} at the best set, {cal['published_worst']:.3g} at the published; "
          f"meets every claim: {cal['meets_all']}", flush=True)
    if rows:
        top = (pd.DataFrame(rows).sort_values("total", ascending=False)
               .groupby(["claim", "quantity"], sort=False).head(1))
        for r in top.itertuples():
            print(f"  {r.claim} {r.quantity}: largest total index {r.factor} "
                  f"{r.total:.2f} [{r.total_lo:.2f}, {r.total_hi:.2f}]")
    return evals, rows, fits, cals


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--prototype", choices=["p1", "p2", "both"], default="both")
    ap.add_argument("--base", type=int, default=8,
                    help="base rows of the Saltelli design (a power of two; 10 points each)")
    ap.add_argument("--starts", type=int, default=2,
                    help="Sobol starts of the calibration, beside the published set")
    ap.add_argument("--iters", type=int, default=40, help="Nelder-Mead iterations per start")
    ap.add_argument("--ensemble-records", type=int,
                    help="also the ensemble claims, with this many records per level "
                         "(the figures use 32)")
    ap.add_argument("--out-dir", default="study_dask")
    ap.add_argument("--workers", type=int, default=2, help="LocalCluster workers")
    ap.add_argument("--scheduler", help="address of a running Dask scheduler")
    ap.add_argument("--slurm-jobs", type=int, help="workers to start as Slurm jobs")
    a = ap.parse_args()

    client = client_for(a)
    client.wait_for_workers(1)
    workers = len(client.scheduler_info()["workers"])
    t0 = time.perf_counter()
    protos = ["p1", "p2"] if a.prototype == "both" else [a.prototype]
    out = [run(client, a, p) for p in protos]
    wall = time.perf_counter() - t0
    client.close()

    os.makedirs(a.out_dir, exist_ok=True)
    evals, rows, fits, cals = (sum((o[i] for o in out), []) for i in range(4))
    pd.DataFrame(evals).to_parquet(os.path.join(a.out_dir, "evaluations.parquet"), index=False)
    pd.DataFrame(rows).to_parquet(os.path.join(a.out_dir, "sobol.parquet"), index=False)
    fits_df = pd.DataFrame(fits).assign(set="fit")
    pd.concat([fits_df, pd.DataFrame(cals)], ignore_index=True).to_parquet(
        os.path.join(a.out_dir, "calibration.parquet"), index=False)
    print(f"{' and '.join(protos)} on {workers} workers in {wall:.0f} s wall; wrote "
          f"{a.out_dir}/evaluations.parquet, sobol.parquet, calibration.parquet")


if __name__ == "__main__":
    main()
