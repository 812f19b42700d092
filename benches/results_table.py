#!/usr/bin/env python3
"""Turns criterion's estimates from `cargo bench -p rdbvh-benches` into the markdown tables of
RESULTS.md: throughput per library (median of the samples, robust to the odd slow sample on a
shared machine) and its ratio to rdbvh.

Usage: python3 benches/results_table.py [CRITERION_DIR]   (default: $CARGO_TARGET_DIR/criterion,
else target/criterion)
"""
import json
import os
import sys
from pathlib import Path

LIBS = ["rdbvh", "rdbvh-reuse", "obvhs-bvh2", "obvhs-cwbvh", "bvh", "parry3d"]


def load(root):
    """{(group, function): M elements per second}"""
    out = {}
    for bench in Path(root).glob("**/new/benchmark.json"):
        meta = json.loads(bench.read_text())
        est = json.loads((bench.parent / "estimates.json").read_text())
        elements = meta["throughput"]["Elements"]
        ns = est["median"]["point_estimate"]
        out[(meta["group_id"], meta["function_id"])] = elements * 1e3 / ns
    return out


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
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(target, "criterion")
    data = load(root)
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
