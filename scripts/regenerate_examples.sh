#!/usr/bin/env bash
# Regenerate every committed example under docs/examples/ (and the README's images made from
# them) with the current code, as the README describes them. About an hour on 2 cores.
# tests/test_examples.py checks that the small example docs/examples/quick still matches.
set -euo pipefail
cd "$(dirname "$0")/.."
AP="${ANCHORPLAN:-anchorplan}"
E=docs/examples

# the small example the tests re-plan (a coarse search; half a minute)
$AP plan --anchors 4 --search-spacing 1.0 --search-chains 2 --search-evaluations 300 \
    --refine-layouts 1 --validate-realizations 5 --no-progress --out $E/quick

# the README command's plan (the paper's experiment: the paper's system), with its report,
# DXF, what-if tables and mounting sheet
$AP plan --anchors 8 --no-progress --out $E/techtile
$AP report $E/techtile
$AP export $E/techtile --dxf $E/techtile/plan.dxf
$AP stress $E/techtile
$AP sheet $E/techtile --out $E/techtile/sheet

# the same room planned for the recommended system (20 ms first-path receiver, echoes
# rejected, positions kept in the room)
$AP plan --anchors 8 --system recommended --no-progress --out $E/techtile-recommended
$AP report $E/techtile-recommended --realizations 0 --figures $E/techtile-recommended/figures

# the office: keep-outs and tag zones
$AP plan --room examples/office.toml --anchors 8 --no-progress --out $E/office
$AP report $E/office --realizations 0 --figures $E/office/figures
$AP export $E/office --dxf $E/office/plan.dxf
$AP stress $E/office
$AP sheet $E/office --out $E/office/sheet

# real rooms: an L-shaped lab with columns, a warehouse with racks; each with its room
# file's system (the paper's receiver) and with the recommended one (the warehouse keeps its
# 60 ms chirp for the reach, its 20 ms window from 40 ms)
for ex in l-shaped-lab:8 warehouse-aisles:10; do
  name=${ex%:*}; M=${ex#*:}
  $AP plan --room examples/$name.toml --anchors $M --no-progress --out $E/$name
  $AP report $E/$name --realizations 0 --figures $E/$name/figures
  $AP sheet $E/$name --out $E/$name/sheet
done
$AP plan --room examples/l-shaped-lab.toml --anchors 8 --system recommended --no-progress \
    --out $E/l-shaped-lab-recommended
$AP report $E/l-shaped-lab-recommended --realizations 0 --figures $E/l-shaped-lab-recommended/figures
$AP plan --room examples/warehouse-aisles.toml --anchors 10 --system recommended \
    --chirp-duration 0.06 --t-wake 0.04 --effort quick --no-progress \
    --out $E/warehouse-aisles-recommended
$AP report $E/warehouse-aisles-recommended --realizations 0 \
    --figures $E/warehouse-aisles-recommended/figures

# how many anchors
$AP sweep --anchors 4-10 --target-p95 2.2 --no-progress --out $E/sweep
$AP report $E/sweep

# the warehouse: how many anchors for 95 % line-of-sight coverage and a P95 of 0.2 m with the
# recommended system
$AP sweep --room examples/warehouse-aisles.toml --system recommended --chirp-duration 0.06 \
    --t-wake 0.04 --anchors 16,18,20,22 --effort quick --target-coverage 0.95 --target-p95 0.2 \
    --no-progress --out $E/warehouse-sweep
$AP report $E/warehouse-sweep
