"""Why the paper deviates, on a Dask cluster: the history match of ``just deviations`` (with
``--history``: waves of runs, every run a task of its own, the emulators fitted between waves
in this process), or the Saltelli Sobol indices and the multi-claim calibration (without it),
with every design point and every calibration start a task of its own.

This is the route for the studies one machine cannot run in the ``just deviations`` budget, above
all those with the ensemble claims of Figures 12, 14 and 15 (``--ensemble-records``: each point
then simulates tens of 10 s records per level). The pieces are the library's own functions
(:mod:`endstop.paper.deviations`), so the numbers are those ``just deviations`` gives for the same
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
    python python/examples/study_dask.py --history --prototype both --per-input 10 \
        --waves 4 --ensemble-records 32 --out-dir history     # the history match

With ``--history`` it writes ``history_runs.parquet`` (every run: wave, point, each quantity),
``history_waves.parquet``, ``history_claims.parquet`` (each claim at each wave: the share it
rules out, its emulator's leave-one-out errors), ``history_projections.parquet`` (each wave's
2-D projections), ``sobol.parquet`` (the emulators' indices), ``run.json`` and ``report.md``
(the answer first).

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
    from endstop.paper import deviations

    factors = deviations.factors()
    points = deviations.design(a.base)
    n = len(points)
    print(f"{proto}: {n} design points, {a.starts + 1} calibration starts", flush=True)
    t0 = time.perf_counter()
    futures = client.map(deviations.evaluate, [proto] * n, list(points), [a.ensemble_records] * n,
                         pure=False)
    progress(futures, "design points")
    evaluations = client.gather(futures)
    sobol_s = time.perf_counter() - t0
    rows = deviations.indices(proto, a.base, evaluations, a.ensemble_records)

    t0 = time.perf_counter()
    k = a.starts + 1
    futures = client.map(deviations.calibrate_start, [proto] * k, range(k), [a.starts] * k,
                         [a.iters] * k, [a.ensemble_records] * k, pure=False)
    progress(futures, "calibration starts")
    cal = deviations.calibration(proto, client.gather(futures), a.ensemble_records)
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


def run_history(client, a, proto):
    """The history match of one prototype: each wave's runs on the workers, the emulators here."""
    from endstop.paper import deviations

    kw = dict(per_input=a.per_input, max_waves=a.waves, pool=a.pool,
              ensemble_records=a.ensemble_records)
    factors = deviations.factors()
    waves, summaries, cells = [], [], []
    t0 = time.perf_counter()
    cpu = 0.0
    state = deviations.history(proto, waves, **kw)
    while state["next_design"] is not None:
        design = [[float(u) for u in p] for p in state["next_design"]]
        n = len(design)
        print(f"{proto}: wave {len(waves) + 1}, {n} runs", flush=True)
        done = evaluate_cached(client, a, proto, design, f"wave {len(waves) + 1}")
        cpu += sum(c for _, c in done)
        waves.append((design, [e for e, _ in done]))
        state = deviations.history(proto, waves, **kw)
        w = state["waves"][-1]
        print(f"  non-implausible {w['non_implausible_fraction']:.4g} of the cube, every claim "
              f"within the cut {w['all_within_cut_fraction']:.4g}; ended: {w['stop']}",
              flush=True)
        cells += [dict(c, prototype=proto) for c in state["projections"]]
    wall = time.perf_counter() - t0
    final = deviations.history(proto, waves, sobol=True, **kw)
    runs = []
    k = 0
    for wave, (design, evals) in enumerate(waves, start=1):
        for point, es in zip(design, evals):
            runs += [dict(e, prototype=proto, run=k, wave=wave, **dict(zip(factors, point)))
                     for e in es]
            k += 1
    times = {"runs": k, "wall_s": wall, "cpu_s_per_run": cpu / max(k, 1),
             "answer": final["answer"]}
    return runs, final, cells, times


def cache_key(proto, point, records):
    """A run's key in the cache: the prototype, the point's coordinates exactly, the records."""
    return json.dumps([proto, [float.hex(u) for u in point], records])


def evaluate_cached(client, a, proto, design, what):
    """The runs of a design, each with its processor time: those of an earlier invocation
    with the same settings from ``--out-dir``'s ``runs-cache.jsonl`` (a study that was stopped
    resumes where it stopped), the others on the workers, appended to the cache as they
    finish."""
    from dask.distributed import as_completed

    path = os.path.join(a.out_dir, "runs-cache.jsonl")
    cached = {}
    if os.path.exists(path):
        with open(path) as f:
            for line in f:
                r = json.loads(line)
                cached[r["key"]] = (r["evaluation"], r["cpu_s"])
    keys = [cache_key(proto, p, a.ensemble_records) for p in design]
    todo = [i for i, k in enumerate(keys) if k not in cached]
    if len(todo) < len(keys):
        print(f"  {what}: {len(keys) - len(todo)} of {len(keys)} runs from {path}", flush=True)
        CACHE_HITS[proto] = CACHE_HITS.get(proto, 0) + len(keys) - len(todo)
    os.makedirs(a.out_dir, exist_ok=True)
    futures = client.map(timed_evaluate, [proto] * len(todo), [design[i] for i in todo],
                         [a.ensemble_records] * len(todo), pure=False)
    index = {f.key: i for f, i in zip(futures, todo)}
    n, done, t0 = len(futures), 0, time.perf_counter()
    with open(path, "a") as f:
        for fut in as_completed(futures):
            e, c = fut.result()
            i = index[fut.key]
            cached[keys[i]] = (e, c)
            f.write(json.dumps({"key": keys[i], "evaluation": e, "cpu_s": c}) + "\n")
            f.flush()
            done += 1
            if done == n or done % max(1, n // 10) == 0:
                print(f"  {what}: {done}/{n} in {time.perf_counter() - t0:.0f} s", flush=True)
    return [cached[k] for k in keys]


# Runs taken from the cache, per prototype (recorded in run.json).
CACHE_HITS = {}


def timed_evaluate(proto, point, records):
    """One run and the processor time it took (for the record's cost per run)."""
    from endstop.paper import deviations

    c0 = time.process_time()
    e = deviations.evaluate(proto, point, records)
    return e, time.process_time() - c0


def pct(x):
    return f"{100 * x:.2g} %"


def history_report(run, finals):
    """The record of a history match as Markdown: the answer of each prototype first, then
    its waves and claims."""
    cmd = " ".join(["python", "python/examples/study_dask.py"] + run["argv"])
    md = []
    for proto, f in finals.items():
        a = f["answer"]
        first = f["waves"][0]
        top = sorted(first["claims"], key=lambda c: -c["ruled_out"])[:3]
        bound = 3 / a["pool"]
        share = (lambda x: f"none of the {a['pool']} pool points (below {pct(bound)})"
                 if x == 0 else pct(x))
        if a["stop"] == "empty":
            verdict = ("**no set within the ranges is consistent with its quantitative claims**: "
                       "the non-implausible space emptied")
        elif a["stop"] == "too few runs to emulate":
            verdict = ("**the waves shrank the non-implausible space below what a design placed "
                       f"in it resolves**: {share(a['fraction'])} of the cube with one claim "
                       f"allowed to miss, {share(a['fraction_all'])} with every claim within "
                       f"the cut; the searches around the survivors found {a['kept_all']} "
                       "points with every claim within the cut, fewer than the next wave's "
                       "emulators need, so the match ends there")
        elif a["none_reproduces"]:
            verdict = ("**no set within the ranges was found consistent with all its "
                       "quantitative claims at once**: allowing one claim to miss, "
                       f"{share(a['fraction'])} of the cube remains, but with every claim "
                       f"within the cut {share(a['fraction_all'])}, no point found near the "
                       "survivors and no run")
        else:
            verdict = ("**sets within the ranges remain consistent with its quantitative "
                       f"claims**: {share(a['fraction_all'])} of the cube ({a['kept_all']} of "
                       "the non-implausible points found, the pool's and those near them) has "
                       "every claim within the cut; "
                       f"{share(a['fraction'])} with one claim allowed to miss")
        md += [f"**Prototype {proto[1:]}** ({a['waves']} wave{'' if a['waves'] == 1 else 's'}, "
               f"{a['runs']} runs, ensemble claims by {run['ensemble_records'] or 'no'} records "
               f"per level): {verdict}; {a['runs_meeting_all']} of the {a['runs']} runs meet "
               "every claim they evaluate directly. "
               "The claims that rule out most of the cube at the first wave: "
               + ", ".join(f"{c['claim']} `{c['quantity']}` ({pct(c['ruled_out'])})"
                           for c in top) + ".", ""]
    md += [f"Recorded run: `{cmd}` on {run['workers']} Dask workers, {run['date']}, endstop "
           f"{run['endstop_version']} at commit `{run['commit']}`; "
           f"{run['ensemble_records'] or 'no'} records per ensemble level, {run['per_input']} "
           f"runs per input per wave, at most {run['waves']} waves, a pool of {run['pool']} "
           "points. Not rerun by the book's build (a test re-evaluates runs of it with the "
           "current code and replays the match from its runs).", ""]
    for proto, f in finals.items():
        t = run["prototypes"][proto]
        hits = run.get("runs_from_cache", {}).get(proto, 0)
        where = (f", {hits} of them from `runs-cache.jsonl` of earlier invocations with the "
                 "same settings (a study resumed)" if hits else "")
        md += [f"**Prototype {proto[1:]}: waves** ({t['runs']} runs{where}; {t['wall_s']:.0f} s "
               f"of wall time in this invocation, {t['cpu_s_per_run']:.1f} s of processor time "
               "per run as measured when each ran)", "",
               "| Wave | Runs | Emulators fitted to | Non-implausible | Every claim within "
               "the cut | Ended |", "|---|---|---|---|---|---|"]
        for w in f["waves"]:
            md.append(f"| {w['wave']} | {w['new_runs']} | {w['training_runs']} | "
                      f"{pct(w['non_implausible_fraction'])} | "
                      f"{pct(w['all_within_cut_fraction'])} | {w['stop'] or '-'} |")
        md += ["", "| Wave | Claim | Quantity | Ruled out | LOO within +-3 |",
               "|---|---|---|---|---|"]
        for w in f["waves"]:
            for c in w["claims"]:
                loo = c["loo"]
                within = (f"{sum(abs(e) <= 3 for e in loo) / len(loo):.0%}" if loo
                          else "constant")
                md.append(f"| {w['wave']} | {c['claim']} | {c['quantity']} | "
                          f"{pct(c['ruled_out'])} | {within} |")
        md.append("")
    return "\n".join(md)


def main_history(a, client, workers, protos):
    import endstop

    t0 = time.perf_counter()
    out = {p: run_history(client, a, p) for p in protos}
    wall = time.perf_counter() - t0
    client.close()
    os.makedirs(a.out_dir, exist_ok=True)
    record = {
        "argv": sys.argv[1:], "date": datetime.date.today().isoformat(),
        "endstop_version": endstop.__version__, "commit": git_commit(), "workers": workers,
        "wall_s": wall, "per_input": a.per_input, "waves": a.waves, "pool": a.pool,
        "ensemble_records": a.ensemble_records,
        "prototypes": {p: o[3] for p, o in out.items()},
        "runs_from_cache": {p: CACHE_HITS.get(p, 0) for p in out},
    }
    finals = {p: o[1] for p, o in out.items()}
    with open(os.path.join(a.out_dir, "run.json"), "w") as f:
        json.dump(record, f, indent=1)
    with open(os.path.join(a.out_dir, "report.md"), "w") as f:
        f.write(history_report(record, finals))
    pd.DataFrame(sum((o[0] for o in out.values()), [])).to_parquet(
        os.path.join(a.out_dir, "history_runs.parquet"), index=False)
    waves = [dict(prototype=p, **{k: v for k, v in w.items() if k not in ("claims", "yes_no_met")})
             for p, f in finals.items() for w in f["waves"]]
    pd.DataFrame(waves).to_parquet(os.path.join(a.out_dir, "history_waves.parquet"), index=False)
    claims = [dict(prototype=p, wave=w["wave"], claim=c["claim"], quantity=c["quantity"],
                   ruled_out=c["ruled_out"], loo_points=len(c["loo"]),
                   loo_within_3=(sum(abs(e) <= 3 for e in c["loo"]) / len(c["loo"])
                                 if c["loo"] else float("nan")))
              for p, f in finals.items() for w in f["waves"] for c in w["claims"]]
    pd.DataFrame(claims).to_parquet(os.path.join(a.out_dir, "history_claims.parquet"),
                                    index=False)
    pd.DataFrame(sum((o[2] for o in out.values()), [])).to_parquet(
        os.path.join(a.out_dir, "history_projections.parquet"), index=False)
    pd.DataFrame(sum((f["indices"] for f in finals.values()), [])).to_parquet(
        os.path.join(a.out_dir, "sobol.parquet"), index=False)
    print(f"{' and '.join(protos)} on {workers} workers in {wall:.0f} s wall; wrote "
          f"{a.out_dir}/history_*.parquet, sobol.parquet, run.json, report.md")


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
    ap.add_argument("--history", action="store_true",
                    help="the history match in waves (instead of the Sobol design and the "
                         "calibration)")
    ap.add_argument("--per-input", type=int, default=10,
                    help="history match: runs per input in each wave")
    ap.add_argument("--waves", type=int, default=4, help="history match: most waves")
    ap.add_argument("--pool", type=int, default=1 << 14,
                    help="history match: uniform pool that measures the space (a power of 2)")
    a = ap.parse_args()

    client = client_for(a)
    client.wait_for_workers(1)
    workers = len(client.scheduler_info()["workers"])
    protos = ["p1", "p2"] if a.prototype == "both" else [a.prototype]
    if a.history:
        main_history(a, client, workers, protos)
        return
    t0 = time.perf_counter()
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
