#!/usr/bin/env python3
"""Tables from bevy-thousand-builds.sh: per round, each run's median CPU ms, each Plume build's
CPU over hanabi's, and each build's own cost above the bare entities (ms)."""
import json
import sys


def main(path):
    rounds = {}
    for line in open(path):
        line = line.strip()
        if not line:
            continue
        row = json.loads(line)
        run = row["run"]
        key = run["plugin"] if run["plugin"] != "plume" else "plume-" + row["build"]
        rounds.setdefault(row["round"], {})[key] = run.get("cpu_ms")
    names = ["empty", "bare", "plume-before", "plume-after", "hanabi"]
    print("| round | " + " | ".join(names) + " | before/hanabi | after/hanabi | before - bare | after - bare |")
    print("|---" * (len(names) + 5) + "|")
    for r in sorted(rounds):
        cpu = rounds[r]
        cells = [f"{cpu[n]:.2f}" if cpu.get(n) is not None else "-" for n in names]

        def ratio(a):
            if cpu.get(a) is None or not cpu.get("hanabi"):
                return "-"
            return f"{cpu[a] / cpu['hanabi']:.3f}"

        def above(a):
            if cpu.get(a) is None or cpu.get("bare") is None:
                return "-"
            return f"{cpu[a] - cpu['bare']:.2f}"

        extra = [ratio("plume-before"), ratio("plume-after"), above("plume-before"), above("plume-after")]
        print(f"| {r} | " + " | ".join(cells + extra) + " |")


if __name__ == "__main__":
    main(sys.argv[1])
