#!/usr/bin/env bash
# The torch plant and the study task's torch env on one GPU (issue 40): equality against
# torch-cpu float64, then plant boat-substeps/s (float32 and float64, eager and torch.compile,
# N = 1e3 .. 1e7) and env steps/s (float32, N = 1e3 .. 1e6; positional eager and compiled,
# radar+goal eager), the open-water env (equality; scene decision steps/s at N = 1e3 .. 1e6,
# radar+goal at 1e3 .. 1e5; equality and scene steps/s in weather),
# then TRPO training on the device (env steps/s of whole iterations).
#
#   bash benchmarks/gpu_check.sh                      # on the GPU machine, from the repo root
#   GPU_CHECK_DEVICE=torch-cpu GPU_CHECK_SIZES=1000,4000 GPU_CHECK_ENV_SIZES=64,256 \
#     GPU_CHECK_TRAIN_SIZES=64,256 GPU_CHECK_OW_SIZES=64,256 GPU_CHECK_OW_RADAR_SIZES=64,256 \
#     GPU_CHECK_COMPILE_BACKEND=eager bash benchmarks/gpu_check.sh   # a dry run on a CPU
#
# Needs python with torch and numpy; nothing of this project is installed (the repository goes on
# PYTHONPATH; no CasADi). Where torch is missing it tries `pip install torch numpy` once and says
# so. Every stage runs under its own time limit inside one overall budget (GPU_CHECK_BUDGET_S,
# default 470 s), writes its results to $OUT/results.jsonl as it goes, and a stage that fails or
# runs out of time does not stop the next. At the end: $OUT/results.json and $OUT/table.txt.
#
# Environment: OUT (default ./gpu-out), GPU_CHECK_DEVICE (cuda), GPU_CHECK_SIZES
# (1000,10000,100000,1000000,10000000), GPU_CHECK_ENV_SIZES (1000,10000,100000,1000000),
# GPU_CHECK_SECONDS (timed seconds per point, 1.0),
# GPU_CHECK_COMPILE_BACKEND (inductor; eager only traces, for a dry run), GPU_CHECK_BUDGET_S,
# GPU_CHECK_LIMIT_SCALE (integer factor on every stage's limit, 1), GPU_CHECK_TRAIN_SIZES
# (1024,8192,32768,65536), GPU_CHECK_OW_SIZES (open-water env, 1000,10000,100000,1000000),
# GPU_CHECK_OW_RADAR_SIZES (its radar+goal, 1000,10000,100000),
# GPU_CHECK_OW_TRAIN_SIZES (open-water scene training, 1024,8192,32768),
# GPU_CHECK_OW_RADAR_TRAIN_SIZES (its radar+goal, 1024,4096), GPU_CHECK_OW_TRAIN_S (0: skipped; seconds of training rl-gaussian-radar-ow on the device,
# benchmarks/gpu_check_ow_train.py, with GPU_CHECK_OW_TRAIN_N boats, 1024, and
# GPU_CHECK_OW_VAL_LIMIT), GPU_CHECK_WHEELS (a folder of wheels: gymnasium and its three small dependencies,
# `pip download -d wheels gymnasium`, installed without network where gymnasium is missing; the
# training stage needs it for its spaces).
set -uo pipefail
cd "$(dirname "$0")/.."
export OUT="${OUT:-./gpu-out}"
mkdir -p "$OUT"
DEVICE="${GPU_CHECK_DEVICE:-cuda}"
SIZES="${GPU_CHECK_SIZES:-1000,10000,100000,1000000,10000000}"
ENV_SIZES="${GPU_CHECK_ENV_SIZES:-1000,10000,100000,1000000}"
TRAIN_SIZES="${GPU_CHECK_TRAIN_SIZES:-1024,8192,32768,65536}"  # boats per TRPO batch (x 64)
OW_SIZES="${GPU_CHECK_OW_SIZES:-1000,10000,100000,1000000}"  # open-water env (scene) boats
OW_RADAR_SIZES="${GPU_CHECK_OW_RADAR_SIZES:-1000,10000,100000}"  # and radar+goal (images)
SECONDS_PER_POINT="${GPU_CHECK_SECONDS:-1.0}"
BACKEND="${GPU_CHECK_COMPILE_BACKEND:-inductor}"
BUDGET="${GPU_CHECK_BUDGET_S:-470}"
LIMIT_SCALE="${GPU_CHECK_LIMIT_SCALE:-1}"  # every stage's limit times this (slow dry runs)
# the first python that has torch (else the first there is: torch gets installed below)
PY=""
for candidate in ${PYTHON:-} python3 python; do
  command -v "$candidate" > /dev/null || continue
  [[ -z $PY ]] && PY="$candidate"
  if "$candidate" -c "import torch" > /dev/null 2>&1; then PY="$candidate"; break; fi
done
[[ -z $PY ]] && { echo "gpu_check: no python found"; exit 1; }
export PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}"
export PYTHONUNBUFFERED=1
LOG="$OUT/log.txt"
START=$(date +%s)
: > "$OUT/results.jsonl"
rm -f "$OUT/reference.npy"
echo "gpu_check: device $DEVICE, sizes $SIZES, budget ${BUDGET}s, out $OUT, $PY" | tee "$LOG"

left() { echo $(( BUDGET - ($(date +%s) - START) )); }

# run NAME LIMIT_S CMD...: the command under min(LIMIT_S, what is left of the budget - 10 s)
run() {
  local name="$1" limit=$(( $2 * LIMIT_SCALE ))
  shift 2
  local remaining=$(( $(left) - 10 ))
  (( remaining < limit )) && limit=$remaining
  if (( limit < 5 )); then
    echo "== $name: skipped (budget spent)" | tee -a "$LOG"
    echo "{\"stage\": \"stage_end\", \"name\": \"$name\", \"status\": \"skipped, budget spent\"}" >> "$OUT/results.jsonl"
    return 0
  fi
  echo "== $name (limit ${limit}s)" | tee -a "$LOG"
  local t0=$(date +%s)
  timeout --kill-after=5 "$limit" "$@" >> "$LOG" 2>&1
  local rc=$? status=ok
  (( rc == 124 || rc == 137 )) && status="timed out"
  (( rc != 0 && rc != 124 && rc != 137 )) && status="failed (exit $rc)"
  local dt=$(( $(date +%s) - t0 ))
  echo "   $name: $status in ${dt}s" | tee -a "$LOG"
  echo "{\"stage\": \"stage_end\", \"name\": \"$name\", \"status\": \"$status\", \"seconds\": $dt}" >> "$OUT/results.jsonl"
  [[ $status == ok ]]
}

# 1. what is there: python, torch (pip-install it where missing), CUDA
if ! "$PY" -c "import torch, numpy" >> "$LOG" 2>&1; then
  echo "torch or numpy missing: trying pip install torch numpy" | tee -a "$LOG"
  run pip-install 240 "$PY" -m pip install --quiet torch numpy
  if ! "$PY" -c "import torch, numpy" >> "$LOG" 2>&1; then
    echo "gpu_check: torch could not be imported or installed; see $LOG" | tee -a "$LOG"
    exit 1
  fi
fi
run env 60 "$PY" benchmarks/gpu_check.py env
if ! "$PY" -c "import gymnasium" > /dev/null 2>&1 && [[ -n ${GPU_CHECK_WHEELS:-} ]]; then
  run gymnasium-install 60 "$PY" -m pip install --quiet --no-index \
    --find-links "$GPU_CHECK_WHEELS" gymnasium
fi
if [[ $DEVICE == cuda* ]] && ! "$PY" -c "import torch, sys; sys.exit(not torch.cuda.is_available())"; then
  echo "gpu_check: torch sees no CUDA GPU (torch.cuda.is_available() is False); see $LOG" | tee -a "$LOG"
  "$PY" benchmarks/gpu_check.py report | tee -a "$LOG"
  exit 1
fi

# 2. equality on the device, float64 and float32, against torch-cpu float64
run equality 90 "$PY" benchmarks/gpu_check.py equality --device "$DEVICE"

# 3. speed: the float32 target first, with torch.compile; then eager; float64 compiled last
bench() {
  run "bench-$1-$2" "$3" "$PY" benchmarks/gpu_check.py bench --device "$DEVICE" --dtype "$1" \
    --mode "$2" --sizes "$SIZES" --seconds "$SECONDS_PER_POINT" --backend "$BACKEND"
}
env_bench() {  # dtype mode limit [observation]
  local obs="${4:-positional}"
  run "env-bench-$obs-$1-$2" "$3" "$PY" benchmarks/gpu_check.py env-bench --device "$DEVICE" \
    --dtype "$1" --mode "$2" --sizes "$ENV_SIZES" --seconds "$SECONDS_PER_POINT" \
    --backend "$BACKEND" --observation "$obs"
}
# most wanted first (a stage gets at most what is left of the budget): the plant's float32
# target, the env's equality and speed, then the rest of the plant table
bench float32 compile 150
run env-equality 60 "$PY" benchmarks/gpu_check.py env-equality --device "$DEVICE"
env_bench float32 eager 60
# the open-water env (scene): equality on the device, then decision steps/s (issue 40)
run ow-equality 60 "$PY" benchmarks/gpu_check_openwater.py equality --device "$DEVICE"
run ow-bench 60 "$PY" benchmarks/gpu_check_openwater.py bench --device "$DEVICE" \
  --sizes "$OW_SIZES" --seconds "$SECONDS_PER_POINT"
run ow-bench-radar 60 "$PY" benchmarks/gpu_check_openwater.py bench --device "$DEVICE" \
  --sizes "$OW_RADAR_SIZES" --seconds "$SECONDS_PER_POINT" --observation radar+goal
# TRPO training on the device (rollouts, GAE, CG and line search there), iterations/s
run train-bench 120 "$PY" benchmarks/gpu_check_train.py --device "$DEVICE" --sizes "$TRAIN_SIZES"
# the same on the open-water env: scene (issue 40's >= 1e6 env steps/s while training) and
# radar+goal (the CNN), with the policy's inference (rollout) and training figures per N
run train-bench-ow-scene 90 "$PY" benchmarks/gpu_check_train.py --device "$DEVICE" \
  --env ow-scene --sizes "${GPU_CHECK_OW_TRAIN_SIZES:-1024,8192,32768}"
run train-bench-ow-radar 90 "$PY" benchmarks/gpu_check_train.py --device "$DEVICE" \
  --env ow-radar --sizes "${GPU_CHECK_OW_RADAR_TRAIN_SIZES:-1024,4096}"
env_bench float32 eager 45 radar+goal
env_bench float32 compile 170  # inductor on the env's ~800-op step: minutes (420 s on 2 CPU cores)
# the open-water env in wind and waves (the weather plant, ~1,000 more ops a plant step):
# equality on the device (three eager runs of 16 boats x 40 decisions), scene decision steps/s
run ow-equality-weather 75 "$PY" benchmarks/gpu_check_openwater.py equality --device "$DEVICE" \
  --weather
run ow-bench-weather 45 "$PY" benchmarks/gpu_check_openwater.py bench --device "$DEVICE" \
  --sizes "$OW_SIZES" --seconds "$SECONDS_PER_POINT" --weather
# the COLREG encounters with the COLREG reward terms on (issue 41's training env): equality
run ow-equality-colreg 45 "$PY" benchmarks/gpu_check_openwater.py equality --device "$DEVICE" \
  --colreg
bench float32 eager 40
bench float64 eager 40
bench float64 compile 100
# the open-water env with the plant + filter step compiled (last: compiling takes minutes)
run ow-bench-compile 150 "$PY" benchmarks/gpu_check_openwater.py bench --device "$DEVICE" \
  --sizes "$OW_SIZES" --seconds "$SECONDS_PER_POINT" --mode compile --backend "$BACKEND"

# optional, not in the 8-minute default (GPU_CHECK_OW_TRAIN_S=300 and a budget that holds it):
# rl-gaussian-radar-ow trained on the device against its shipped model's validation figures
if (( ${GPU_CHECK_OW_TRAIN_S:-0} > 0 )); then
  run ow-train $(( GPU_CHECK_OW_TRAIN_S * 2 + 120 )) "$PY" benchmarks/gpu_check_ow_train.py run \
    --device "$DEVICE" --seconds "$GPU_CHECK_OW_TRAIN_S" --n-envs "${GPU_CHECK_OW_TRAIN_N:-1024}" \
    --val-limit "${GPU_CHECK_OW_VAL_LIMIT:-0}"
fi

"$PY" benchmarks/gpu_check.py report 2>&1 | tee -a "$LOG"
rm -f "$OUT/reference.npy"  # 7 MB of intermediate numbers
echo "gpu_check: done in $(( $(date +%s) - START ))s; $OUT/table.txt, $OUT/results.json, $OUT/log.txt"
