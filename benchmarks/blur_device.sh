#!/bin/bash
# Device A/B of the bilateral blur (BENCHMARKS.md, "The bilateral blur: both axes in one kernel, the sums opened and
# closed in the taps"): benchmarks/post_device.sh for the bilateral blur alone. Run from the checkout root where both
# trees sit, with the wheels installed in /tmp/site and the environment of the device calls:
#   bash .dev/TREE/benchmarks/blur_device.sh .dev/MAIN .dev/TREE OUTDIR
# Writes OUTDIR/cpu.txt, post_ab.jsonl (post_ab.py's bilateral blur of both trees in fresh processes, medians of 9) and
# blur.json (benchmarks/blur_variants.py, every VARIANTS name in one process, 8 rounds).
PASSES=bilateral_blur_hv RADIAL="" BLUR=${VARIANTS:-"tree main ymm planes512 blocks1 exp_ymm frame no_exp"} REPEATS=9 \
  ROUNDS=4 exec bash "$(dirname "$0")/post_device.sh" "$@"
