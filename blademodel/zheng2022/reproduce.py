"""``blademodel reproduce fig06|all``: reproduce the paper's figures."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from ..sweep import load_study, open_result
from ..sweep.claims import check_claims, claims_table, tally
from .studies import paper_figures, summarize
from ..commands.sweep import add_run_arguments, default_out, execute


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``reproduce`` subcommand."""
    p = subparsers.add_parser("reproduce", help="reproduce the paper's figures (fig05 ... fig19, or all)",
                              description="Run a paper figure's study from models/studies and write its data "
                                          "(NetCDF), its figures (PNG) and a summary into the output folder.")
    p.add_argument("figure", nargs="+", metavar="FIGURE", help="fig05 ... fig19, or all")
    p.add_argument("--out", default="out", metavar="DIR", help="output folder (default: out)")
    add_run_arguments(p)
    p.set_defaults(run=run)
    return p


def run(args: argparse.Namespace) -> int:
    """Reproduce the figures; return the exit code (1 if every point of a figure failed)."""
    known = paper_figures()
    names = sorted(known) if "all" in args.figure else args.figure
    unknown = [n for n in names if n not in known]
    if unknown:
        raise ValueError(f"unknown figure {', '.join(unknown)}; known: {', '.join(known)} or all")
    summary, failed = {}, 0
    for name in names:
        study = load_study(known[name])
        out = default_out(Path(args.out), name, args.quick)
        t0 = time.perf_counter()
        figures, ok = execute(study, out, args)
        failed += not ok
        seconds = time.perf_counter() - t0
        entry = {"title": study.title, "paper": study.paper, "seconds": round(seconds, 1),
                 "data": str(out), "figures": [str(f) for f in figures]}
        if study.cases or study.claims:
            ds = open_result(out)
            if study.cases:
                entry["cases"] = summarize(ds)
            if study.claims:
                entry["claims"] = check_claims(study, ds)
        summary[name] = entry
        print(f"{name}: {study.title} ({seconds:.0f} s)")
        for row in entry.get("cases", []):
            values = ", ".join(f"{k} = {v:g}" for k, v in row.items() if k not in ("law", "motion", "lyapunov", "events"))
            lam = f", lambda = {row['lyapunov']:+.3f}/period" if row.get("lyapunov") is not None else ""
            print(f"    {row['law']:8s} {values}: {row['motion']}{lam}")
        if study.paper:
            print(f"    paper: {study.paper}")
    path = Path(args.out) / ("summary_quick.json" if args.quick else "summary.json")
    previous = json.loads(path.read_text()) if path.exists() else {}
    merged = {k: v for k, v in {**previous, **summary}.items() if k != "claims_tally"}
    rows = [row for name in sorted(merged) for row in merged[name].get("claims", [])]
    if rows:
        agree, measured = tally(rows)
        merged["claims_tally"] = {"agree": agree, "measured": measured, "claims": len(rows)}
        print("\nThe paper's case points beside what was measured" + (" (--quick: coarse runs)" if args.quick else "")
              + (f", with the figures of earlier runs in {path}" if set(merged) - set(summary) - {"claims_tally"}
                 else "") + ":")
        for line in claims_table(rows):
            print("    " + line)
    path.write_text(json.dumps(merged, indent=2))
    print(f"summary: {path}")
    return 1 if failed else 0
