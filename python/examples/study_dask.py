"""Why the paper deviates, on a Dask cluster: the Sobol indices and the multi-claim calibration
of ``just deviations``, with every design point and every calibration start a task of its own.

This is the route for the studies one machine cannot run in the ``just deviations`` budget, above
all those with the ensemble claims of Figures 12, 14 and 15 (``--ensemble-records``: each point
then simulates tens of 10 s records per level). The pieces are the library's own functions
(:mod:`endstop.paper.study`), so the numbers are those ``just deviations`` gives for the same
settings.

Writes, under ``--out-dir``:

* ``evaluations.parquet``: every design point (its unit-cube coordinates) and every quantity
  there (outcome, value, normalised deviation, met or not);
* ``sobol.parquet``: the indices, with the columns of the study's own ``sobol.parquet``;
* ``calibration.parquet``: every start's fit, and the best and the published set's
  evaluations;
* ``run.json`` (the command, the settings, the package's version and git commit, the workers
  and the wall times) and ``report.md`` (the calibration's table and the largest indices, as
  the book includes a recorded run).

    pip install "./python[dask]"
    python python/examples/study_dask.py --prototype p2 --base 4 --ensemble-records 32 \
        --out-dir study-p2                          # a LocalCluster on this machine
    python python/examples/study_dask.py --scheduler tcp://host:8786 ...   # a cluster
    python python/examples/study_dask.py --slurm-jobs 64 ...               # Slurm workers

With ``--slurm-jobs N`` the script starts N one-core workers as Slurm jobs (dask-jobqueue);
for any other scheduler start the workers yourself and pass ``--scheduler``.
"""

import argparse
import datetime
import json
import os
import subprocess
import sys
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
    times = {"design_points": n, "design_s": sobol_s, "calibration_starts": k,
             "calibration_s": cal_s, "worst": cal["worst"],
             "published_worst": cal["published_worst"], "meets_all": cal["meets_all"]}
    return evals, rows, fits, cals, times


def git_commit():
    """The repository's commit (with ``-dirty`` for uncommitted changes), if there is one."""
    here = os.path.dirname(os.path.abspath(__file__))
    try:
        return subprocess.run(["git", "describe", "--always", "--dirty", "--abbrev=12"],
                              cwd=here, capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def fmt(x):
    return "-" if x is None or x != x else f"{x:.4g}"


def report(run, evals, rows, cals):
    """The run's record as Markdown: what ran, the calibration per prototype, the indices."""
    cmd = " ".join(["python", "python/examples/study_dask.py"] + run["argv"])
    md = [f"Recorded run: `{cmd}` on {run['workers']} Dask workers, {run['date']}, endstop "
          f"{run['endstop_version']} at commit `{run['commit']}`; "
          f"{run['ensemble_records'] or 'no'} records per ensemble level, Saltelli design of "
          f"{run['base']} base rows, the published set and {run['starts']} Sobol "
          f"start{'' if run['starts'] == 1 else 's'} (each of at "
          f"most {run['iters']} Nelder-Mead iterations). Not rerun by the book's build (a test "
          f"re-evaluates its published and best sets with the current code).", ""]
    ev = pd.DataFrame(evals)
    cal = pd.DataFrame(cals)
    ix = pd.DataFrame(rows)
    for proto, t in run["prototypes"].items():
        met = cal[(cal.prototype == proto) & (cal.set == "best")]
        md += [f"**Prototype {proto[1:]}.** {t['design_points']} design points in "
               f"{t['design_s']:.0f} s and {t['calibration_starts']} calibration starts in "
               f"{t['calibration_s']:.0f} s of wall time. Worst |normalised deviation| over "
               f"the quantitative claims: {t['worst']:.3g} at the best set found, "
               f"{t['published_worst']:.3g} at the published set; the best set meets "
               f"{int(met.meets.sum())} of {len(met)} claims.", ""]
        md += ["| Claim | Quantity | Unit | Paper | Published set | Deviation | Best set | "
               "Deviation | Met |", "|---|---|---|---|---|---|---|---|---|"]
        pub = cal[(cal.prototype == proto) & (cal.set == "published")].set_index(
            ["claim", "quantity"])
        for r in met.itertuples():
            p = pub.loc[(r.claim, r.quantity)]
            val = lambda e: fmt(e.value) if e.outcome == "value" else e.outcome
            md.append(f"| {r.claim} | {r.quantity} | {r.unit} | {fmt(r.paper)} | {val(p)} | "
                      f"{fmt(p.deviation)} | {val(r)} | {fmt(r.deviation)} | "
                      f"{'yes' if r.meets else 'no'} |")
        md.append("")
        sub = ix[ix.prototype == proto] if len(ix) else ix
        if len(sub):
            md += ["Largest total Sobol index of each quantity (95 % bootstrap interval), and "
                   "the share of design points where the quantity is absent:", "",
                   "| Claim | Quantity | Factor | Total index | Interval | Absent |",
                   "|---|---|---|---|---|---|"]
            top = (sub.sort_values("total", ascending=False)
                   .groupby(["claim", "quantity"], sort=False).head(1)
                   .sort_values(["claim", "quantity"]))
            for r in top.itertuples():
                md.append(f"| {r.claim} | {r.quantity} | {r.factor} | {r.total:.2f} | "
                          f"[{r.total_lo:.2f}, {r.total_hi:.2f}] | {r.absent_share:.0%} |")
            md.append("")
        n = ev[ev.prototype == proto].point.nunique()
        md += [f"({n} design points in `evaluations.parquet`, the indices of every factor in "
               f"`sobol.parquet`, every start's fit in `calibration.parquet`.)", ""]
    return "\n".join(md)


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

    import endstop

    os.makedirs(a.out_dir, exist_ok=True)
    evals, rows, fits, cals = (sum((o[i] for o in out), []) for i in range(4))
    record = {
        "argv": sys.argv[1:], "date": datetime.date.today().isoformat(),
        "endstop_version": endstop.__version__, "commit": git_commit(), "workers": workers,
        "wall_s": wall, "base": a.base, "starts": a.starts, "iters": a.iters,
        "ensemble_records": a.ensemble_records,
        "prototypes": {p: o[4] for p, o in zip(protos, out)},
    }
    with open(os.path.join(a.out_dir, "run.json"), "w") as f:
        json.dump(record, f, indent=1)
    with open(os.path.join(a.out_dir, "report.md"), "w") as f:
        f.write(report(record, evals, rows, cals))
    pd.DataFrame(evals).to_parquet(os.path.join(a.out_dir, "evaluations.parquet"), index=False)
    pd.DataFrame(rows).to_parquet(os.path.join(a.out_dir, "sobol.parquet"), index=False)
    fits_df = pd.DataFrame(fits).assign(set="fit")
    pd.concat([fits_df, pd.DataFrame(cals)], ignore_index=True).to_parquet(
        os.path.join(a.out_dir, "calibration.parquet"), index=False)
    print(f"{' and '.join(protos)} on {workers} workers in {wall:.0f} s wall; wrote "
          f"{a.out_dir}/evaluations.parquet, sobol.parquet, calibration.parquet, run.json, "
          f"report.md")


if __name__ == "__main__":
    main()
