"""A label table's text against the standard library's writers, in process.

    python benchmarks/bench_table_text.py                     # 256^3, 100,000 labels
    python benchmarks/bench_table_text.py --labels 1000 --repeat 3 --json ''

Input: the grain map of ``benchmarks/bench_labels.py`` (cached in
``benchmarks/.cache/``) and its table, ``isoflow.label_table(image)``.
Timed, warm, alternated, best of ``--repeat``, each checked equal first:

* ``--json``'s text (``isoflow.cli.table_text.json_rows``) against
  ``json.dumps`` of a list of one dict per row (what a script writes);
* ``--csv``'s text (``csv_rows``) against ``csv.writer`` over the rows;
* the float columns alone (the centroids: 3 per row): their cells
  (``cell_bytes``: the compiled shortest round-trip text,
  ``isoflow.scale.float_text``) against ``repr`` of each float, the text
  both writers above hold.

The whole command (``isoflow info FILE --labels --json``) is timed by
``benchmarks/bench_labels.py --commands N``.
Results: ``benchmarks/results/table_text.json`` (``--json``) and a
Markdown table on stdout.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))


def cells_of(table: dict) -> list[list]:
    """The table's cells as the standard library takes them (tuples as
    lists, NaN and infinities as None)."""
    return [[list(v) if isinstance(v, tuple) else None if isinstance(v, float) and not np.isfinite(v) else v
             for v in column.tolist()] for column in table.values()]


def std_json(table: dict) -> str:
    cells = cells_of(table)
    return json.dumps([dict(zip(table, row)) for row in zip(*cells)])


def std_csv(table: dict) -> str:
    cells = cells_of(table)
    fh = io.StringIO()
    writer = csv.writer(fh)
    writer.writerow(list(table))
    writer.writerows(zip(*[[";".join(map(str, v)) if isinstance(v, list) else v for v in column]
                            for column in cells]))
    return fh.getvalue()


def main(argv=None) -> int:
    from bench_labels import cached

    from isoflow import label_table
    from isoflow.cli.table_text import cell_bytes, csv_rows, json_rows

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--labels", type=int, default=100_000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--json", default=str(ROOT / "benchmarks" / "results" / "table_text.json"))
    args = ap.parse_args(argv)

    path = cached(args.size, args.labels)
    table = label_table(np.load(path))
    floats = np.ascontiguousarray(np.concatenate([table[f"centroid-{d}"] for d in range(3)]))
    chars, lengths = cell_bytes(floats, "null", "", ("", ""))  # a float column's cells, as the writers take them
    texts = [bytes(row[len(row) - n:]).decode() for row, n in zip(chars, lengths)]
    assert texts == [repr(v) for v in floats.tolist()], "the float text differs from repr"
    pairs = {
        "json": (lambda: "".join(json_rows(table)), lambda: std_json(table), "json.dumps(list of dicts)"),
        "csv": (lambda: "".join(csv_rows(table)), lambda: std_csv(table), "csv.writer"),
        "floats": (lambda: cell_bytes(floats, "null", "", ("", "")), lambda: [repr(v) for v in floats.tolist()],
                   "repr per float"),
    }
    assert pairs["json"][0]() == pairs["json"][1](), "json text differs"
    assert pairs["csv"][0]() == pairs["csv"][1](), "csv text differs"
    best = {name: [float("inf"), float("inf")] for name in pairs}
    for _ in range(args.repeat):
        for name, (ours, theirs, _) in pairs.items():
            for k, fn in enumerate((ours, theirs)):
                t = time.perf_counter()
                fn()
                best[name][k] = min(best[name][k], time.perf_counter() - t)
    rows = [{"what": name, "cells": len(floats) if name == "floats" else len(table["label"]) * len(table),
             "isoflow_seconds": best[name][0], "other": pairs[name][2], "other_seconds": best[name][1],
             "ratio": best[name][1] / best[name][0]} for name in pairs]
    print(f"| {args.size}^3, {args.labels:,} labels ({len(table['label']):,} rows) | cells | isoflow s | "
          "standard library | s | ratio |")
    print("|---|---:|---:|---|---:|---:|")
    for r in rows:
        print(f"| {r['what']} | {r['cells']:,} | {r['isoflow_seconds']:.3f} | {r['other']} | "
              f"{r['other_seconds']:.3f} | {r['ratio']:.1f}x |")
    if args.json:
        meta = {"command": "python benchmarks/bench_table_text.py " + " ".join(argv or sys.argv[1:]),
                "machine": platform.processor() or platform.machine(), "input": str(path.relative_to(ROOT))}
        Path(args.json).write_text(json.dumps({**meta, "results": rows}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
