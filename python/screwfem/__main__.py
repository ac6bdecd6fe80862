"""Command line of the Python package: `python3 -m screwfem sweep ...` (`screwfem sweep` runs it).

    python3 -m screwfem sweep SCENE --grid key=v1,v2,... [--grid ...]
                              [--samples N --seed S --range key=low,high ...]
                              [--scheduler ADDR | --workers N] -o DIR [--resume]
                              [--metric point:P8@0.5,1] [--keep-outputs] [--quiet]

A thin front end to screwfem.sweep: prints the summary table (short parameter names, status,
metrics) and one line, writes DIR/summary.csv, DIR/figures/METRIC.png, DIR/results.csv (and
DIR/rows.jsonl, DIR/sweep.json), and keeps the files of the variants that did not complete and
of each metric's smallest and largest value in DIR/runs/. A grid key may name several override paths joined with '+'
(all set to the same value). Values are YAML scalars; a value holding commas goes in
brackets: --grid 'gravity=[0,0,-9.81],[0,0,-1.62]'.
Exit codes: 0 every variant completed, 1 some did not (failed, invalid or error rows), 2
invalid usage, 130 interrupted (the finished rows are kept; --resume continues).
"""

import argparse
import sys


def _split_values(text):
    """'a,b,[c,d]' -> ['a', 'b', '[c,d]'] (commas inside brackets or braces stay)."""
    out, depth, cur = [], 0, ""
    for ch in text:
        if ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        if ch == "," and depth == 0:
            out.append(cur)
            cur = ""
        else:
            cur += ch
    out.append(cur)
    return [v.strip() for v in out]


def _parse_value(text):
    """A command-line value: int or float when it reads as one (so that sweeps from the CLI and
    from Python with the same numbers have the same variant ids), else the text."""
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def _key_value(text, option):
    key, sep, values = text.partition("=")
    if not sep or not key or not values:
        raise SystemExit(f"screwfem sweep: {option} expects KEY=VALUES, got '{text}'")
    return key, _split_values(values)


def _metric(text, sf):
    """--metric point:NAME@t1,t2 | effort[:J0,J2] | constraint | counters | wall, or an
    expression over a recorded column: max(C) min(C) absmax(C) initial(C) final(C) mean(C)
    rms(C) at(C,T) (screwfem.ColumnMetric)."""
    if "(" in text:
        try:
            return sf.ColumnMetric(text)
        except ValueError as e:
            raise SystemExit(f"screwfem sweep: {e}") from None
    kind, _, arg = text.partition(":")
    if kind == "point":
        name, _, times = arg.partition("@")
        return sf.PointPosition(name, [float(t) for t in times.split(",")])
    if kind == "effort":
        return sf.PeakJointEffort(arg.split(",") if arg else None)
    simple = {"constraint": sf.MaxConstraintResidual, "counters": sf.Counters, "wall": sf.WallTime}
    if kind in simple and not arg:
        return simple[kind]()
    raise SystemExit(f"screwfem sweep: unknown metric '{text}' "
                     "(point:NAME@T1,T2 | effort[:J1,J2] | constraint | counters | wall | "
                     "max(COLUMN) | min | absmax | initial | final | mean | rms | at(COLUMN,T))")


def main(argv=None):
    parser = argparse.ArgumentParser(prog="screwfem", description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("sweep", help="run many variants of a scene (Dask)")
    p.add_argument("scene", help="scene file (YAML)")
    p.add_argument("--grid", action="append", default=[], metavar="KEY=V1,V2,...",
                   help="a grid axis (repeatable; keys joined with '+' share the value)")
    p.add_argument("--samples", type=int, help="N random variants instead of a grid")
    p.add_argument("--seed", type=int, default=0, help="seed of the random samples (default 0)")
    p.add_argument("--range", action="append", default=[], metavar="KEY=LOW,HIGH",
                   help="a sampled parameter, uniform on [LOW, HIGH) (with --samples)")
    p.add_argument("--scheduler", help="Dask scheduler address tcp://HOST:PORT, or 'serial'")
    p.add_argument("--workers", type=int, help="local worker processes (default: all cores)")
    p.add_argument("--metric", action="append", default=[],
                   help="point:NAME@T1,T2 | effort[:J1,J2] | constraint | counters | wall | "
                        "max(COLUMN) | min(C) | absmax(C) | initial(C) | final(C) | mean(C) | "
                        "rms(C) | at(C,T), C a column of any table of the run, e.g. "
                        "'max(tip.z)' (repeatable; default: constraint, counters, wall)")
    p.add_argument("-o", "--output", required=True, help="output directory")
    p.add_argument("--resume", action="store_true", help="run only the variants missing in -o")
    p.add_argument("--keep-outputs", action="store_true",
                   help="keep every variant's files in OUTPUT/runs/VARIANT_ID/ (default: only "
                        "those of the variants that did not complete and of the smallest and "
                        "largest value of each metric)")
    p.add_argument("--max-memory", metavar="SIZE",
                   help="refuse variants whose model and solver would need more memory than "
                        "SIZE, e.g. 8G (default: half the physical memory; docs/limits.md)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress line")
    args = parser.parse_args(argv)

    import screwfem as sf

    if args.samples is not None:
        if args.grid or not args.range:
            parser.error("--samples takes --range KEY=LOW,HIGH parameters (and no --grid)")
        parameters = {}
        for text in args.range:
            key, values = _key_value(text, "--range")
            if len(values) != 2:
                parser.error(f"--range expects KEY=LOW,HIGH, got '{text}'")
            parameters[key] = (float(values[0]), float(values[1]))
    else:
        if not args.grid:
            parser.error("give at least one --grid KEY=V1,V2,... (or --samples N --range ...)")
        parameters = {}
        for text in args.grid:
            key, values = _key_value(text, "--grid")
            parameters[key] = [_parse_value(v) for v in values]
    metrics = [_metric(m, sf) for m in args.metric] or list(sf.DEFAULT_METRICS)

    try:
        df = sf.sweep(args.scene, parameters, metrics=metrics, scheduler=args.scheduler,
                      workers=args.workers, outdir=args.output, samples=args.samples,
                      seed=args.seed, resume=args.resume,
                      keep_outputs=True if args.keep_outputs else "notable",
                      progress=False if args.quiet else None, max_memory=args.max_memory,
                      summary=True)
    except KeyboardInterrupt:
        print(f"\nscrewfem sweep: interrupted; finished rows kept in {args.output} "
              "(--resume runs the missing variants)", file=sys.stderr)
        return 130
    except (OSError, ValueError, TypeError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    counts = df["status"].value_counts().to_dict() if len(df) else {}
    summary = ", ".join(f"{n} {s}" for s, n in sorted(counts.items()))
    if len(df):
        print(sf.format_summary(sf.summary_table(df, list(parameters))))
    print(f"sweep: {len(df)} variants ({summary}) -> {args.output}/summary.csv, results.csv, "
          "figures/")
    notable = df.attrs.get("notable", {})
    if notable:
        print(f"kept in {args.output}/runs/: " +
              "; ".join(f"{vid} ({why})" for vid, why in notable.items()))
    for _, row in df[df["status"] != "completed"].iterrows():
        print(f"  {row['variant_id']} {row['status']}: {row['message']}", file=sys.stderr)
    return 0 if counts.get("completed", 0) == len(df) else 1


if __name__ == "__main__":
    sys.exit(main())
