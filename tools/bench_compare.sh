#!/bin/sh
# SPDX-License-Identifier: BSD-3-Clause
# bench_compare.sh OLD NEW ROUNDS [bench options] - two sandslide binaries'
# `bench --json` side by side: ROUNDS rounds, the binary that goes first
# alternating (ABBA, so an order effect cancels), then per case the median
# over rounds of each run's median cell-updates/s, new/old, and the
# per-round ratios (their spread is the machine's noise).  Example:
#
#   tools/bench_compare.sh ../baseline/build/sandslide build/sandslide 10 \
#       --surface supercritical --threads 1
old=$1 new=$2 rounds=$3
[ -x "$old" ] && [ -x "$new" ] && [ "$rounds" -ge 1 ] 2>/dev/null ||
	{ sed -n '2,9p' "$0"; exit 2; }
shift 3
d=$(mktemp -d "${TMPDIR:-/tmp}/bench_compare.XXXXXX")
for r in $(seq 1 "$rounds"); do
	if [ $((r % 2)) -eq 1 ]; then order="old new"; else order="new old"; fi
	for which in $order; do
		bin=$old
		[ "$which" = new ] && bin=$new
		"$bin" bench --json "$@" > "$d/${which}_$r.json" || exit 1
	done
done
/usr/bin/python3 - "$d" "$rounds" <<'PY'
import json, statistics, sys
d, rounds = sys.argv[1], int(sys.argv[2])
def load(which):
    out = {}
    for r in range(1, rounds + 1):
        for c in json.load(open(f"{d}/{which}_{r}.json"))["cases"]:
            key = (c["surface"], c["closure"], c["threads"])
            out.setdefault(key, []).append(c["cell_updates_per_s"]["median"])
    return out
old, new = load("old"), load("new")
print(f"{'surface':14} {'closure':22} {'thr':>3} {'old':>10} {'new':>10} {'new/old':>7}  per round")
for k in old:
    o, n = statistics.median(old[k]), statistics.median(new[k])
    rounds_ = " ".join(f"{b / a:.3f}" for a, b in zip(old[k], new[k]))
    print(f"{k[0]:14} {k[1]:22} {k[2]:>3} {o:10.4g} {n:10.4g} {n / o:7.3f}  {rounds_}")
PY
rm -rf "$d"
