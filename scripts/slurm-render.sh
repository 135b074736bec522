#!/usr/bin/env bash
# Render a scene on a Slurm cluster: one array task per tile of rows, then a
# merge job that runs once every tile has succeeded (--dependency=afterok).
#
#   scripts/slurm-render.sh SCENE.json OUT_DIR TILES [extra `irsig render` args...]
#
# e.g. scripts/slurm-render.sh scenes/town/scene.json out/town 16 --times 2025-06-21T14:00:00-04:00
#
# Environment (all optional):
#   IRSIG            path of the irsig binary (default: ./target/release/irsig)
#   SLURM_PARTITION  partition for both jobs
#   SLURM_TIME       time limit per tile task (default 01:00:00)
#   SLURM_CPUS       CPUs per tile task (default 4); passed to --threads
#   SLURM_MEM        memory per tile task (default 8G)
#   SLURM_ACCOUNT    account to charge
#
# Each task writes OUT_DIR/NAME.tileK-of-N.exr atomically; a tile that is
# already complete is skipped, so resubmitting the same command after a
# failure redoes only the missing tiles. The merge job checks that every
# tile is present and consistent (same scene hash and size) and writes
# OUT_DIR/NAME.exr, NAME.img/.hdr and NAME.png. Logs go to OUT_DIR/slurm/.
set -euo pipefail

if [[ $# -lt 3 ]]; then
    sed -n '2,22p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
fi
scene=$1
out=$2
tiles=$3
shift 3
if ! [[ $tiles =~ ^[1-9][0-9]*$ ]]; then
    echo "slurm-render.sh: TILES must be a positive integer, got '$tiles'" >&2
    exit 2
fi
[[ -f $scene ]] || { echo "slurm-render.sh: no scene file '$scene'" >&2; exit 2; }
command -v sbatch >/dev/null || { echo "slurm-render.sh: sbatch not found (is this a Slurm login node?)" >&2; exit 2; }

irsig=${IRSIG:-./target/release/irsig}
[[ -x $irsig ]] || { echo "slurm-render.sh: no irsig binary at '$irsig' (build with cargo build --release, or set IRSIG)" >&2; exit 2; }
irsig=$(realpath "$irsig")
scene=$(realpath "$scene")
mkdir -p "$out/slurm"
out=$(realpath "$out")

common=()
[[ -n ${SLURM_PARTITION:-} ]] && common+=(--partition="$SLURM_PARTITION")
[[ -n ${SLURM_ACCOUNT:-} ]] && common+=(--account="$SLURM_ACCOUNT")
cpus=${SLURM_CPUS:-4}

# Quote the extra arguments for the job scripts.
extra=""
for a in "$@"; do extra+=" $(printf '%q' "$a")"; done

array_id=$(sbatch --parsable "${common[@]}" \
    --job-name=irsig-tiles \
    --array="1-$tiles" \
    --cpus-per-task="$cpus" \
    --mem="${SLURM_MEM:-8G}" \
    --time="${SLURM_TIME:-01:00:00}" \
    --output="$out/slurm/tile-%a.log" \
    --wrap="$(printf '%q' "$irsig") render $(printf '%q' "$scene") -o $(printf '%q' "$out") --tile \${SLURM_ARRAY_TASK_ID}/$tiles --threads $cpus --quiet$extra")
array_id=${array_id%%;*}

merge_id=$(sbatch --parsable "${common[@]}" \
    --job-name=irsig-merge \
    --dependency="afterok:$array_id" \
    --cpus-per-task="$cpus" \
    --mem="${SLURM_MEM:-8G}" \
    --time=00:30:00 \
    --output="$out/slurm/merge.log" \
    --wrap="$(printf '%q' "$irsig") merge $(printf '%q' "$out")/*.tile*-of-$tiles.exr -o $(printf '%q' "$out") --threads $cpus")
merge_id=${merge_id%%;*}

echo "submitted tiles: job array $array_id (1-$tiles); merge: job $merge_id (after all tiles succeed)"
echo "outputs: $out ; logs: $out/slurm/"
