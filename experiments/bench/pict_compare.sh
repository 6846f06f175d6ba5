#!/usr/bin/env bash
# paracosm-cover's covering arrays against PICT's on the models in pict_models/ (four with
# constraints, one uniform): rows of PICT (its default seed, and the best of /r:2, /r:3 when
# it is given), of paracosm's IPOG alone (--optimise 0), of its default (2 s for a small
# model) and of --optimise 60, with the wall time of the last.
#
#   bash experiments/bench/pict_compare.sh [PICT_BINARY]
#
# PICT is built from source (github.com/microsoft/pict, `cmake -DCMAKE_BUILD_TYPE=Release`),
# never vendored; without it the PICT columns read "-". Every paracosm array is checked by
# the test suite's own coverage count, not here.
set -euo pipefail
cd "$(dirname "$0")/../.."
pict="${1:-}"
cargo build --release --locked --bin paracosm-cover >/dev/null
cover=target/release/paracosm-cover
models=experiments/bench/pict_models
rows() { tail -n +2 | grep -c .; }
echo "| model | t | PICT (default; best of /r:2, /r:3) | paracosm IPOG | default (2 s) | --optimise 60 | its time |"
echo "|---|---:|---:|---:|---:|---:|---:|"
for run in c3_12:2 c3_12:3 c4_8:2 c4_8:3 c5_10:2 c5_10:3 cmixed:2 cmixed:3 u5_10:2 u5_10:3 u5_10:4; do
  m="${run%%:*}"; t="${run##*:}"; f="$models/$m.txt"
  p="-"
  if [ -n "$pict" ]; then
    d=$("$pict" "$f" /o:"$t" | rows)
    r=$(for s in 2 3; do "$pict" "$f" /o:"$t" /r:"$s" | rows; done | sort -n | head -1)
    p="$d; $r"
  fi
  plain=$("$cover" generate --model "$f" --strength "$t" --optimise 0 | rows)
  default=$("$cover" generate --model "$f" --strength "$t" | rows)
  start=$(date +%s.%N)
  long=$("$cover" generate --model "$f" --strength "$t" --optimise 60 | rows)
  secs=$(echo "$(date +%s.%N) - $start" | bc)
  printf '| %s | %s | %s | %s | %s | %s | %.1f s |\n' "$m" "$t" "$p" "$plain" "$default" "$long" "$secs"
done
