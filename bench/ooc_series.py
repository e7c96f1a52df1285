#!/usr/bin/env python3
"""Tables and plot of bench/ooc_series.sh: param's time, peak memory and scratch traffic against
faces. Reads RUNS/<faces>.json (param's report) and RUNS/<faces>.time (GNU time -v), writes a CSV,
and a markdown table with the slope between the two largest sizes extrapolated to 1G faces (the
plot comes from bench_scaling_report).

  python3 bench/ooc_series.py RUNS --csv F --md F [--command TEXT]
"""
import argparse
import json
import os
import re
import sys


def read_runs(folder):
    runs = []
    for name in os.listdir(folder):
        m = re.fullmatch(r"(\d+)\.json", name)
        if not m:
            continue
        with open(os.path.join(folder, name)) as f:
            r = json.load(f)
        peak = r.get("peakResidentBytes", 0)
        time_path = os.path.join(folder, m.group(1) + ".time")
        if os.path.exists(time_path):
            with open(time_path) as f:
                for line in f:
                    if "Maximum resident set size" in line:
                        peak = max(peak, int(line.split()[-1]) * 1024)
        # In memory the field's directions go to the scratch file once per cone pass and are read
        # back once; out of core every stage's traffic is in the report.
        disk = r.get("fieldBytesOnDisk", 0)
        stages = r.get("scratch", {}).get("stages", [])
        written = sum(t["bytesWritten"] for t in stages) if stages else disk
        read = sum(t["bytesRead"] for t in stages) if stages else disk
        outOfCore = r.get("path") == "out-of-core"
        runs.append({
            "faces": r["faces"],
            "seconds": r["seconds"]["total"],
            "peak": peak,
            "budget": r.get("memoryBudget", 0),
            "estimate": r.get("estimatedBytes", 0),
            "written": written,
            "read": read,
            "scratchPeak": r.get("scratch", {}).get("peakBytes", disk),
            "onDisk": disk > 0,
            "path": "out of core" if outOfCore else "memory, field on disk" if disk > 0 else "memory",
            "passes": r.get("conePasses", 0),
            "cones": r.get("cones", 0),
            "flips": r.get("quality", {}).get("flipped", 0),
            "seamless": r.get("quality", {}).get("seamless", False),
        })
    runs.sort(key=lambda x: x["faces"])
    return runs


GIB = float(1 << 30)


def markdown(runs, command):
    lines = [
        "```",
        command,
        "```",
        "",
        "| faces | time s | s per M faces | peak GiB | B per face | estimate GiB | budget GiB | path | scratch peak GiB | scratch written / read GiB | cone passes | cones | flips | seamless |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in runs:
        lines.append("| %.1fM | %.1f | %.2f | %.2f | %.1f | %.2f | %.2f | %s | %.2f | %.2f / %.2f | %d | %d | %d | %s |" % (
            r["faces"] / 1e6, r["seconds"], r["seconds"] / (r["faces"] / 1e6), r["peak"] / GIB,
            r["peak"] / r["faces"], r["estimate"] / GIB, r["budget"] / GIB, r["path"], r["scratchPeak"] / GIB,
            r["written"] / GIB, r["read"] / GIB, r["passes"], r["cones"], r["flips"], "yes" if r["seamless"] else "NO"))
    if len(runs) >= 2:
        a, b = runs[-2], runs[-1]
        dn = b["faces"] - a["faces"]
        if dn > 0:
            ts = (b["seconds"] - a["seconds"]) / dn
            ps = (b["peak"] - a["peak"]) / dn
            g = 1e9
            lines += ["", "Slope from %.0fM to %.0fM faces: %.2f s per million faces, %.1f B per face; "
                      "extrapolated to 1G faces: %.0f min, %.0f GiB." % (
                          a["faces"] / 1e6, b["faces"] / 1e6, ts * 1e6, ps,
                          (b["seconds"] + ts * (g - b["faces"])) / 60.0, (b["peak"] + ps * (g - b["faces"])) / GIB)]
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("runs")
    ap.add_argument("--csv", required=True)
    ap.add_argument("--md", required=True)
    ap.add_argument("--command", default="bash bench/ooc_series.sh")
    a = ap.parse_args()
    runs = read_runs(a.runs)
    if not runs:
        sys.exit("no runs in " + a.runs)
    with open(a.csv, "w") as f:
        f.write("faces,seconds,peak_bytes,estimate_bytes,budget_bytes,field_on_disk,out_of_core,scratch_peak,scratch_written,scratch_read,cone_passes,cones\n")
        for r in runs:
            f.write("%d,%.3f,%d,%d,%d,%d,%d,%d,%d,%d,%d,%d\n" % (r["faces"], r["seconds"], r["peak"], r["estimate"], r["budget"],
                                                            r["onDisk"], r["path"] == "out of core", r["scratchPeak"],
                                                            r["written"], r["read"], r["passes"], r["cones"]))
    with open(a.md, "w") as f:
        f.write(markdown(runs, a.command))
    sys.stdout.write(markdown(runs, a.command))


if __name__ == "__main__":
    main()
