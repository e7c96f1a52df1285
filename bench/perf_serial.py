"""Where one core works alone: `perf` samples of a `seamvox param` run binned by the report's
stages, counting the 20 ms windows in which only one thread sampled, with the functions sampled
in them. Usage:

    perf record -F 499 -o perf.data -- seamvox param X -o out.ply --report r.json
    perf script -i perf.data -F tid,time,ip,sym | python3 bench/perf_serial.py r.json [TOP]

The stages are laid end to end back from the last sample (the report's stage seconds)."""
import collections
import json
import re
import sys


def main():
    report = json.load(open(sys.argv[1]))
    top = int(sys.argv[2]) if len(sys.argv) > 2 else 12
    samples = []
    for line in sys.stdin:
        m = re.match(r'\s*(\d+)\s+([\d.]+):\s+[0-9a-f]+\s+(.*)', line)
        if m:
            samples.append((int(m.group(1)), float(m.group(2)), re.sub(r'\+0x[0-9a-f]+$', '', m.group(3).strip())))
    if not samples:
        sys.exit("no samples: run perf script with -F tid,time,ip,sym")
    stages = report['stages']
    start = samples[-1][1] - sum(s['seconds'] for s in stages)
    window = 0.02
    threads = collections.defaultdict(set)
    for tid, t, _ in samples:
        threads[int((t - start) / window)].add(tid)
    t = start
    for stage in stages:
        a, b = t, t + stage['seconds']
        t = b
        alone = collections.Counter(sym for tid, ts, sym in samples
                                    if a <= ts < b and len(threads[int((ts - start) / window)]) == 1)
        windows = sum(1 for k, tids in threads.items() if a <= start + k * window < b and len(tids) == 1)
        print(f"== {stage['name']} {b - a:.2f} s: ~{windows * window:.2f} s in one-thread windows")
        for sym, n in alone.most_common(top):
            print(f"   {n:6d} samples  {sym[:120]}")


if __name__ == '__main__':
    main()
