#!/usr/bin/env bash
# The star discrepancy of a sampler's points restricted to a valid region (a constraint
# that cuts the unit square to its left half or third), measured against the region, beside
# the same sampler run on the region itself. docs/coverage.md quotes its output.
#
#   bash experiments/bench/valid_discrepancy.sh [PATH/TO/paracosm-cover]
set -euo pipefail
cover=${1:-target/release/paracosm-cover}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
space() { # name, upper bound of x, optional constraint
    {
        printf '[[param]]\nname = "x"\ninterval = [0.0, %s]\n\n' "$2"
        printf '[[param]]\nname = "y"\ninterval = [0.0, 1.0]\n'
        if [ -n "${3:-}" ]; then printf '\n[[constraint]]\nname = "cut"\nrequire = "%s"\n' "$3"; fi
    } > "$dir/$1.toml"
}
space half_cut 1.0 "x < 0.5"
space half 0.5
space third_cut 1.0 "x < 1.0 / 3"
space third 0.3333333333333333
star() { "$cover" estimate --space "$dir/$1.toml" "$2" --metrics star | awk '/star discrepancy/ {print $3}'; }
echo "n strategy region filtered on-the-region ratio"
for n in 256 1024 4096; do
    for s in halton sobol random; do
        for region in half third; do
            "$cover" generate --space "$dir/${region}_cut.toml" --strategy "$s" --budget "$n" --seed 1 > "$dir/f.csv"
            "$cover" generate --space "$dir/$region.toml" --strategy "$s" --budget "$n" --seed 1 > "$dir/p.csv"
            a=$(star "$region" "$dir/f.csv")
            b=$(star "$region" "$dir/p.csv")
            echo "$n $s $region $a $b $(python3 -c "print(f'{$a / $b:.2f}')")"
        done
    done
done
