#!/usr/bin/env python3
"""Turns criterion's estimates from `cargo bench -p rdbvh-benches` into the markdown tables of
RESULTS.md: throughput per library (median of the samples, robust to the odd slow sample on a
shared machine) and its ratio to rdbvh.

Usage: python3 benches/results_table.py [CRITERION_DIR...]   (default: $CARGO_TARGET_DIR/criterion,
else target/criterion). With several directories (copies of criterion/ from several runs), each
cell is the median over the runs: on a shared machine one run can be slowed as a whole.
"""
import json
import os
import statistics
import sys
from pathlib import Path

LIBS = ["rdbvh", "rdbvh-reuse", "rdbvh-wide", "obvhs-bvh2", "obvhs-cwbvh", "bvh", "parry3d"]


def load(roots):
    """{(group, function): M elements per second}, the median over the runs in `roots`"""
    runs = {}
    for root in roots:
        for bench in Path(root).glob("**/new/benchmark.json"):
            meta = json.loads(bench.read_text())
            est = json.loads((bench.parent / "estimates.json").read_text())
            elements = meta["throughput"]["Elements"]
            ns = est["median"]["point_estimate"]
            key = (meta["group_id"], meta["function_id"])
            runs.setdefault(key, []).append(elements * 1e3 / ns)
    return {key: statistics.median(values) for key, values in runs.items()}


def cell(data, group, lib):
    v = data.get((group, lib))
    base = data.get((group, "rdbvh"))
    if v is None:
        return "-"
    if lib == "rdbvh" or base is None:
        return f"{v:.2f}"
    return f"{v:.2f} ({v / base:.2f}x)"


def table(data, columns):
    head = "| library | " + " | ".join(title for title, _ in columns) + " |"
    rule = "|---|" + "---:|" * len(columns)
    rows = []
    for lib in LIBS:
        cells = [cell(data, group, lib) for _, group in columns]
        if all(c == "-" for c in cells):
            continue
        rows.append(f"| `{lib}` | " + " | ".join(cells) + " |")
    return "\n".join([head, rule] + rows)


def main():
    target = os.environ.get("CARGO_TARGET_DIR", "target")
    roots = sys.argv[1:] or [os.path.join(target, "criterion")]
    data = load(roots)
    for scene, label in [("bunny", "bunny"), ("sponza_crytek", "Sponza")]:
        print(f"\nTraversal on the {label}:\n")
        print(
            table(
                data,
                [
                    ("build bunny Mtris/s", "build/bunny"),
                    ("build Sponza Mtris/s", "build/sponza_crytek"),
                    ("closest camera Mrays/s", f"traverse/{scene}/closest-camera"),
                    ("closest random Mrays/s", f"traverse/{scene}/closest-random"),
                    ("any camera Mrays/s", f"traverse/{scene}/any-camera"),
                    ("any random Mrays/s", f"traverse/{scene}/any-random"),
                ],
            )
        )


if __name__ == "__main__":
    main()
