"""The history match in pieces: the runs on Dask workers equal the runs here, the match
replayed from its runs is the match, and the recorded definitive match is what this code
computes (within the ensembles' sampling error)."""

import json
import math
import pathlib

import pytest

from endstop.paper import deviations

RECORDED = pathlib.Path(__file__).resolve().parents[2] / "data" / "recorded" / "history"

# The tolerances of the recorded minimax runs' test: a recorded ensemble value may differ from
# today's by RECORDED_Z standard errors of the difference of two independent estimates; values
# without sampling error to RECORDED_RTOL, located events to twice the locator's tolerance.
from test_paper_deviations import LOCATED_EVENTS, RECORDED_RTOL, RECORDED_Z  # noqa: E402

SMALL = dict(per_input=2, max_waves=1, pool=1 << 10)


def test_a_wave_on_dask_workers_is_the_wave_here_and_the_replay_is_deterministic():
    import dask.distributed as distributed  # the test extra installs it
    first = deviations.history("p2", [], **SMALL)
    design = [[float(u) for u in p] for p in first["next_design"]]
    assert len(design) == SMALL["per_input"] * len(deviations.factors())
    here = [deviations.evaluate("p2", p) for p in design]
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
    with cluster, distributed.Client(cluster) as client:
        there = client.gather(client.map(deviations.evaluate, ["p2"] * 4, design[:4], pure=False))
    assert there == here[:4]
    a = deviations.history("p2", [(design, here)], **SMALL)
    b = deviations.history("p2", [(design, here)], **SMALL)
    assert a["waves"] == b["waves"] and a["projections"] == b["projections"]
    (w,) = a["waves"]
    assert w["stop"] == "last wave" and a["next_design"] is None
    assert [(c["claim"], c["quantity"]) for c in w["claims"]] == [tuple(o) for o in a["outputs"]]
    assert 0.0 <= w["all_within_cut_fraction"] <= w["non_implausible_fraction"] <= 1.0
    # Every claim's leave-one-out errors are one per training run.
    assert all(len(c["loo"]) in (0, w["training_runs"]) for c in w["claims"])


def test_points_that_are_not_the_waves_design_are_refused():
    first = deviations.history("p2", [], **SMALL)
    design = [[float(u) for u in p] for p in first["next_design"]]
    fake = [list(reversed(p)) for p in design]
    evals = [deviations.evaluate("p2", design[0])] * len(design)
    with pytest.raises(ValueError, match="design"):
        deviations.history("p2", [(fake, evals)], **SMALL)


def recorded_runs(pd, proto):
    runs = pd.read_parquet(RECORDED / "history_runs.parquet")
    return runs[runs["prototype"] == proto]


def test_the_recorded_history_match_is_what_this_code_computes():
    # The recording is part of the repository: a missing one fails, it is not skipped.
    assert (RECORDED / "run.json").exists(), f"no recorded history match in {RECORDED}"
    import pandas as pd  # the test extra installs it
    run = json.loads((RECORDED / "run.json").read_text())
    waves_rec = pd.read_parquet(RECORDED / "history_waves.parquet")
    kw = dict(per_input=run["per_input"], max_waves=run["waves"], pool=run["pool"],
              ensemble_records=run["ensemble_records"])
    factors = deviations.factors()
    for proto in run["prototypes"]:
        rows = recorded_runs(pd, proto)
        waves = []
        for wave, by_wave in rows.groupby("wave", sort=True):
            design, evals = [], []
            for _, r in by_wave.groupby("run", sort=True):
                design.append([float(r[f].iloc[0]) for f in factors])
                evals.append([dict(claim=x.claim, quantity=x.quantity, outcome=x.outcome,
                                   value=float(x.value),
                                   ci95=None if x.ci95 != x.ci95 else float(x.ci95))
                              for x in r.itertuples()])
            waves.append((design, evals))
        # The match replayed from the recorded runs gives the recorded shares, exactly (the
        # emulators' fit is deterministic).
        replay = deviations.history(proto, waves, **kw)
        rec = waves_rec[waves_rec["prototype"] == proto].sort_values("wave")
        assert [w["non_implausible_fraction"] for w in replay["waves"]] == list(
            rec["non_implausible_fraction"]), proto
        assert [w["all_within_cut_fraction"] for w in replay["waves"]] == list(
            rec["all_within_cut_fraction"]), proto
        # The first two runs of the first wave, evaluated again now.
        for point, then in list(zip(*waves[0]))[:2]:
            now = deviations.evaluate(proto, point, run["ensemble_records"])
            assert [(e["claim"], e["quantity"], e["outcome"]) for e in now] == [
                (e["claim"], e["quantity"], e["outcome"]) for e in then]
            for e, t in zip(now, then):
                what = (proto, e["claim"], e["quantity"], e["value"], t["value"])
                if e["ci95"] is None:
                    located = 2.0 * LOCATED_EVENTS.get(e["quantity"], 0.0)
                    assert e["value"] == pytest.approx(t["value"], rel=RECORDED_RTOL,
                                                       abs=located), what
                else:
                    allowed = RECORDED_Z * math.sqrt(2.0) * e["ci95"] / 1.96
                    assert abs(e["value"] - t["value"]) <= allowed, what + (allowed,)
