"""``maizeviz sweep SPEC --out DIR``: run a sweep file's scenarios on Dask.

Exit codes: 0 every scenario done; 1 nothing could be done (bad sweep file, output folder,
scheduler); 2 bad command-line usage; 3 done, but some scenarios are in error (bad input) or
failed (listed in the results' status and error columns); 130 interrupted (rerun to resume).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from maizeviz.errors import MaizevizError
from maizeviz.numbers import NUMBER_ARG, WHOLE_ARG

EXIT_OK, EXIT_FAIL, EXIT_USAGE, EXIT_PARTIAL, EXIT_INTERRUPTED = 0, 1, 2, 3, 130
#: The subcommand (``maizeviz.cli`` lists this module among its commands).
NAME = "sweep"


def _say(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _add_arguments(p: argparse.ArgumentParser) -> None:
    from maizeviz.sweep.run import CONNECT_TIMEOUT_S
    from maizeviz.sweep.spec import MAX_SCENARIOS
    from maizeviz.sweep.summary import DEFAULT_TOLERANCE

    p.add_argument("spec", metavar="SPEC", help="sweep file (TOML): canopy, level and sun axes")
    p.add_argument("--out", metavar="DIR",
                   help="results folder: results.parquet, results.csv, summary.csv, sweep.json")
    p.add_argument("--workers", type=WHOLE_ARG, metavar="N",
                   help="worker processes of the local Dask cluster (default: one per core)")
    p.add_argument("--scheduler", metavar="ADDR",
                   help="use a running Dask scheduler, e.g. tcp://10.0.0.5:8786, instead of a "
                        "local cluster (workers need maizeviz and the points files)")
    p.add_argument("--connect-timeout", type=NUMBER_ARG, default=CONNECT_TIMEOUT_S, metavar="S",
                   help=f"seconds to wait for --scheduler (default {CONNECT_TIMEOUT_S:g})")
    p.add_argument("--dry-run", action="store_true",
                   help="list the scenarios and estimate the work; compute nothing")
    p.add_argument("--resume", action=argparse.BooleanOptionalAction, default=True,
                   help="skip scenarios already in --out for the same sweep (default); "
                        "--no-resume computes them again")
    p.add_argument("--force", action="store_true",
                   help="use --out even when it holds another sweep or other files")
    p.add_argument("--yes", action="store_true",
                   help=f"run more than {MAX_SCENARIOS:,} scenarios")
    p.add_argument("--tolerance", type=NUMBER_ARG, default=DEFAULT_TOLERANCE, metavar="T",
                   help="summary: largest transmission difference from the finest level "
                        f"(default {DEFAULT_TOLERANCE:g})")
    p.add_argument("--no-progress", dest="progress", action="store_false", default=None,
                   help="no progress bar, even on a terminal")


def add_sweep_parser(subparsers) -> argparse.ArgumentParser:
    """Add the ``sweep`` subcommand to a ``maizeviz`` argument parser."""
    p = subparsers.add_parser(
        "sweep", help="run many canopies, mesh levels and suns on Dask (local or a cluster)",
        description="Run every scenario of a sweep file (the product of its canopy, level "
                    "and sun axes) on a Dask cluster, write one row per scenario and height to "
                    "DIR/results.parquet and results.csv as they finish, and summarise the "
                    "cheapest mesh level within --tolerance of the finest. Rerunning resumes.")
    _add_arguments(p)
    p.set_defaults(run=run_sweep)
    return p


#: The interface of a ``maizeviz.cli`` command module.
add_parser = add_sweep_parser


def run_sweep(args) -> int:
    """Run the ``sweep`` subcommand; returns the exit code (messages on stderr)."""
    from maizeviz.sweep.spec import load_spec

    if not args.dry_run and not args.out:
        _say("error: give --out DIR for the results (or --dry-run)")
        return EXIT_USAGE
    from maizeviz.sweep.run import max_local_workers

    if args.workers is not None and not 1 <= args.workers <= max_local_workers():
        _say(f"error: --workers must be from 1 to {max_local_workers()} on this machine (4 a "
             f"core), got {args.workers:,}")
        return EXIT_USAGE
    if not (args.tolerance >= 0):
        _say(f"error: --tolerance must be >= 0, got {args.tolerance}")
        return EXIT_USAGE
    from maizeviz.sweep.run import check_connect_timeout

    try:
        check_connect_timeout(args.connect_timeout)
    except MaizevizError as exc:
        _say(f"error: --connect-timeout: {exc}")
        return EXIT_USAGE
    if args.workers is not None and args.scheduler:
        _say("error: --workers sizes the local cluster; with --scheduler the cluster has its own")
        return EXIT_USAGE
    try:
        spec = load_spec(args.spec, yes=args.yes)
        if args.dry_run:
            return _dry_run(spec, args)
        check_paths(spec, args.out)
        if not args.scheduler:                       # a cluster's workers have their own memory
            check_memory(spec)
        return _run(spec, args)
    except MaizevizError as exc:
        _say(f"error: {exc}")
        return EXIT_FAIL


def check_paths(spec, out) -> None:
    """Refuse, before any work, a results folder whose files would overwrite the sweep file,
    a points file or a layout file of the sweep."""
    from maizeviz.io.outputs import OutputFolder, check_run_paths

    inputs = [("the sweep file", spec.source)]
    for s in spec.scenarios:
        inputs.append(("the points file", s.points.path))
        if s.arrangement.layout_path:
            inputs.append(("the layout file", s.arrangement.layout_path))
    files = ("results.parquet", "results.csv", "summary.csv", "sweep.json")
    check_run_paths([], list(dict.fromkeys(inputs)),
                    [OutputFolder("the results folder", out, files)])


def _run(spec, args) -> int:
    from maizeviz.sweep.run import run_sweep as run
    from maizeviz.sweep.store import read_results
    from maizeviz.sweep.summary import format_summary, summarize, write_summary

    groups = len(spec.groups())
    _say(f"{spec.source}: {len(spec.scenarios)} scenarios in {groups} canopies "
         f"({spec.excluded} excluded)")
    outcome = run(spec, args.out, workers=args.workers, scheduler=args.scheduler,
                  connect_timeout=args.connect_timeout, resume=args.resume, force=args.force,
                  progress=args.progress)
    out = Path(args.out)
    rows = read_results(out) if (out / "results.parquet").exists() else []
    summary = summarize(rows, args.tolerance)
    if rows:
        write_summary(out / "summary.csv", summary)
    if not outcome.interrupted:
        print(format_summary(summary))
    ok = sum(1 for r in rows if r["status"] == "ok") // max(1, len(spec.scenarios[0].heights_cm))
    bad = outcome.errors + outcome.failed
    _say(f"{outcome.already_done + outcome.computed} of {outcome.total} scenarios in {out} "
         f"({outcome.computed} computed now in {outcome.seconds:.1f} s, "
         f"{outcome.already_done} already there"
         + (f", {bad} in error: see the status and error columns" if bad else "") + ")")
    if outcome.interrupted:
        return EXIT_INTERRUPTED
    if ok == 0:
        _say("error: no scenario could be computed")
        return EXIT_FAIL
    errors_on_disk = sum(1 for r in rows if r["status"] != "ok")
    return EXIT_PARTIAL if bad or errors_on_disk else EXIT_OK


def _dry_run(spec, args) -> int:
    from maizeviz.sweep import compute
    from maizeviz.sweep.store import done_keys_on_disk

    done = done_keys_on_disk(args.out, spec) if args.out else set()
    from maizeviz.sweep.spec import optics_label

    optics = any(s.optics is not None for s in spec.scenarios)
    head = ["#", "key", "points", "arrangement", "level", "sun", "density", "periodic",
            *(["optics"] if optics else []), ""]
    rows = [[s.index + 1, s.key[:12], s.points.name, s.arrangement.label, s.level, s.sun.label,
             f"{s.density:g}", "yes" if s.periodic else "no",
             *([optics_label(s.optics)] if optics else []),
             "done" if s.key in done else ""] for s in spec.scenarios]
    cells = [head] + [[str(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(head))]
    for r in cells:
        print("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip())

    groups = spec.groups()
    workers = args.workers or os.cpu_count() or 1
    cpu = 0.0
    triangles = rays = peak = 0
    problems = []
    for g in groups:
        try:
            canopy, cover, *light = compute.group_costs(g)
        except MaizevizError as exc:
            problems.append(f"{g[0].points.name}, {g[0].arrangement.label}, {g[0].level}: {exc}")
            continue
        triangles += canopy.count
        rays += sum(c.count for c in light)
        peak = max(peak, canopy.bytes + cover.bytes + max(c.bytes for c in light))
        cpu += canopy.seconds + cover.seconds + sum(c.seconds for c in light)
    todo = len(spec.scenarios) - len(done)
    print()
    print(f"{len(spec.scenarios)} scenarios ({spec.excluded} excluded"
          + (f", {len(done)} already in {args.out}" if done else "") + f") in {len(groups)} "
          f"canopies (points x arrangement x level: one canopy, measure and Embree scene each)")
    print(f"{triangles:,} triangles to build, {rays:,} rays to trace; the largest canopy needs "
          f"about {peak / 2**30:.1f} GiB on its worker")
    print(f"estimate: about {cpu:,.0f} CPU seconds, {cpu / workers:,.0f} s on {workers} "
          "workers (maizeviz's cost model, the same as the canopy and light commands', "
          "measured on a 2-core machine; yours may differ)"
          + ("" if todo == len(spec.scenarios) else f"; {todo} scenarios left to compute"))
    for p in problems:
        _say(f"warning: {p}")
    return EXIT_OK


def check_memory(spec) -> None:
    """Refuse a local sweep whose largest group would not fit in this machine's memory
    (``maizeviz.cost``); a group that cannot be estimated (a bad file) is left to run and be
    recorded as an error."""
    from maizeviz.cost import check
    from maizeviz.sweep import compute

    stages = []
    for g in spec.groups():
        try:
            canopy, cover, *light = compute.group_costs(g)
        except MaizevizError:
            continue
        stages.append([canopy, cover, max(light, key=lambda c: c.bytes)])
    check(stages, force=True)


def main(argv=None) -> int:
    """``python -m maizeviz.sweep SPEC --out DIR ...`` (the same as ``maizeviz sweep``)."""
    p = argparse.ArgumentParser(prog="maizeviz sweep", description=(
        "Run every scenario of a sweep file on Dask and summarise the cheapest mesh level."))
    _add_arguments(p)
    args = p.parse_args(argv)
    try:
        return run_sweep(args)
    except KeyboardInterrupt:
        _say("interrupted")
        return EXIT_INTERRUPTED
