#!/usr/bin/env bash
# Re-run every published row of one shipped model after its file was replaced (another seed's
# weights under the same name: the seed rule of docs/notes/2026-12-seeds.md) or first shipped
# (its rows are then added), and write them into the committed data, guide tables and model
# card. Run from the repository root, after `python benchmarks/train_rl.py --setups SETUP
# --ship-only` (or train_il.py, or benchmarks/ship_traffic.py) wrote the file:
#
#   bash benchmarks/reship.sh radar-categorical-trpo-openwater-continued R
#
# R keeps each run's JSON; a run whose file is there is not run again, so a cut-off call goes on
# where it stopped. The runs, all with the committed episode counts:
#   stress-validation.json  usvsim bench --suite stress --split validation (26 sets, 100 each)
#   stress-test.json        the same, test split
#   calm-twin.json          the weather sets' calm twin (benchmarks/weather_stress_table.py)
#   colreg.json             usvsim bench --suite colreg --colreg-episodes 20 (test)
#   bench.json              usvsim bench (the study task: validation and held-out episodes)
# Then: docs/data/stress.json, stress-weather.json, stress-weather-calm.json and bench.json
# (benchmarks/stress_merge.py --replace-helmsmen), the COLREG suite's tables in
# docs/guide/colreg-suite.md (benchmarks/colreg_table.py --replace), the tracker and weather
# guide tables (benchmarks/reship_docs.py), the model card's stress figures and the recommended
# marks (benchmarks/model_cards.py: validation first, the marks, then test). Read the prose
# around the tables afterwards (git diff): it names figures the scripts do not write.
set -euo pipefail
if [ $# -ne 2 ]; then
  echo "usage: bash benchmarks/reship.sh MODEL OUT_DIR" >&2
  exit 2
fi
model=$1
out=$2
mkdir -p "$out"

run() { # FILE COMMAND...: COMMAND's stdout to OUT/FILE unless that file exists (atomic)
  local file=$out/$1
  shift
  if [ -s "$file" ]; then
    echo "reship: $file exists, not run again"
    return
  fi
  local t0=$SECONDS
  "$@" >"$file.part"
  mv "$file.part" "$file"
  echo "reship: $file in $((SECONDS - t0)) s"
}

run stress-validation.json usvsim bench --suite stress --helmsmen "$model" --split validation \
  --json --no-plots
run stress-test.json usvsim bench --suite stress --helmsmen "$model" --split test --json --no-plots
run calm-twin.json python benchmarks/weather_stress_table.py calm-twin --helmsmen "$model"
run colreg.json usvsim bench --suite colreg --helmsmen "$model" --colreg-episodes 20 --json \
  --no-plots
run bench.json usvsim bench --helmsmen "$model" --json --no-plots

merge() { # DATA NEW: replace the model's rows in DATA, or add them where DATA has none (new model)
  if python -c "import json, sys; rows = json.load(open(sys.argv[1]))['rows']
sys.exit(0 if any(r['helmsman'] == sys.argv[2] for r in rows) else 1)" "$1" "$model"; then
    python benchmarks/stress_merge.py --replace-helmsmen "$model" "$1" "$2"
  else
    python benchmarks/stress_merge.py "$1" "$2"
  fi
}
for data in stress stress-weather; do
  merge "docs/data/$data.json" "$out/stress-test.json"
done
merge docs/data/stress-weather-calm.json "$out/calm-twin.json"
merge docs/data/bench.json "$out/bench.json"
python benchmarks/colreg_table.py "$out/colreg.json" --replace docs/guide/colreg-suite.md
python benchmarks/colreg_table.py "$out/stress-test.json" --replace docs/guide/colreg-suite.md
python benchmarks/reship_docs.py "$model"
# the cards hold the sets of docs/data/stress.json (the 22 original sets), as every other card
python benchmarks/model_cards.py --stress "$out/stress-validation.json" \
  --sets-of docs/data/stress.json --recommend
python benchmarks/model_cards.py --stress "$out/stress-test.json" --sets-of docs/data/stress.json
echo "reship: $model done; read git diff for the prose"
