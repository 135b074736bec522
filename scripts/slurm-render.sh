#!/usr/bin/env bash
# Render a scene on a Slurm cluster, splitting both the per-facet stage and
# the image rows:
#   1. pass 1, a job array: each task traces the rays of its share of the
#      facets (irsig thermal-scene --pass 1 --shard K/N);
#   2. pass 2, a job array after all of pass 1 (--dependency=afterok): the
#      thermal passes, each task writing its share of the facet states;
#   3. the tiles, a job array after pass 2: each task renders its band of
#      rows from the state (irsig render --state DIR --tile K/N);
#   4. the merge, after every tile (irsig merge).
#
#   scripts/slurm-render.sh SCENE.json OUT_DIR TILES [extra `irsig render` args...]
#
# e.g. scripts/slurm-render.sh scenes/town/scene.json out/town 16 --times 2025-06-21T14:00:00-04:00
#
# Environment (all optional):
#   IRSIG               path of the irsig binary (default: ./target/release/irsig)
#   SLURM_PASS1_SHARDS  tasks of pass 1 (default: TILES)
#   SLURM_PASS2_SHARDS  tasks of pass 2 (default 1: each task runs the thermal
#                       passes over every facet and writes its share)
#   SLURM_PARTITION     partition for every job
#   SLURM_TIME          time limit per task (default 01:00:00)
#   SLURM_CPUS          CPUs per task (default 4); passed to --threads
#   SLURM_MEM           memory per task (default 8G)
#   SLURM_ACCOUNT       account to charge
#   SLURM_LOCAL=1       no Slurm: run the same commands here, one after another
#
# Every file is written atomically and every step skips what is already
# complete (the same scene, times and settings), so resubmitting the same
# command after a failure redoes only what is missing. The state goes to
# OUT_DIR/state (docs/cluster.md describes it), the images to OUT_DIR,
# logs to OUT_DIR/slurm/. Of the extra arguments, --times, --backend,
# --facet-samples and --sky-sampling go to every step; the rest only to
# the render.
set -euo pipefail

if [[ $# -lt 3 ]]; then
    sed -n '2,34p' "$0" | sed 's/^# \{0,1\}//'
    exit 2
fi
scene=$1
out=$2
tiles=$3
shift 3
positive() { [[ $2 =~ ^[1-9][0-9]*$ ]] || { echo "slurm-render.sh: $1 must be a positive integer, got '$2'" >&2; exit 2; }; }
positive TILES "$tiles"
pass1=${SLURM_PASS1_SHARDS:-$tiles}
pass2=${SLURM_PASS2_SHARDS:-1}
positive SLURM_PASS1_SHARDS "$pass1"
positive SLURM_PASS2_SHARDS "$pass2"
[[ -f $scene ]] || { echo "slurm-render.sh: no scene file '$scene'" >&2; exit 2; }
local_run=${SLURM_LOCAL:-0}
if [[ $local_run != 1 ]]; then
    command -v sbatch >/dev/null || { echo "slurm-render.sh: sbatch not found (is this a Slurm login node? SLURM_LOCAL=1 runs here)" >&2; exit 2; }
fi

irsig=${IRSIG:-./target/release/irsig}
[[ -x $irsig ]] || { echo "slurm-render.sh: no irsig binary at '$irsig' (build with cargo build --release, or set IRSIG)" >&2; exit 2; }
irsig=$(realpath "$irsig")
scene=$(realpath "$scene")
mkdir -p "$out/slurm"
out=$(realpath "$out")
state=$out/state

common=()
[[ -n ${SLURM_PARTITION:-} ]] && common+=(--partition="$SLURM_PARTITION")
[[ -n ${SLURM_ACCOUNT:-} ]] && common+=(--account="$SLURM_ACCOUNT")
cpus=${SLURM_CPUS:-4}

# Quote the extra arguments for the job scripts; those that change the
# per-facet state go to every step.
extra=""
shared=""
take=0
for a in "$@"; do
    q=" $(printf '%q' "$a")"
    extra+=$q
    if [[ $take == 1 ]]; then
        shared+=$q
        take=0
        continue
    fi
    case $a in
        --times|--backend|--facet-samples|--sky-sampling) shared+=$q; take=1 ;;
        --times=*|--backend=*|--facet-samples=*|--sky-sampling=*) shared+=$q ;;
    esac
done

qi=$(printf '%q' "$irsig")
qs=$(printf '%q' "$scene")
qo=$(printf '%q' "$out")
qst=$(printf '%q' "$state")

# submit NAME TASKS DEPENDENCY LOG COMMAND: an array job of TASKS tasks (1:
# a single job) after job DEPENDENCY (may be empty); prints its id. With
# SLURM_LOCAL=1 the tasks run here in turn (SLURM_ARRAY_TASK_ID set), and
# a failing task stops the chain.
submit() {
    local name=$1 tasks=$2 dep=$3 log=$4 cmd=$5
    if [[ $local_run == 1 ]]; then
        local k
        for ((k = 1; k <= tasks; k++)); do
            SLURM_ARRAY_TASK_ID=$k bash -c "$cmd" >"$out/slurm/${log//%a/$k}" 2>&1 \
                || { echo "slurm-render.sh: $name task $k failed; see $out/slurm/${log//%a/$k}" >&2; exit 1; }
        done
        echo "local-$name"
        return
    fi
    local args=("${common[@]}" --job-name="$name" --cpus-per-task="$cpus"
        --mem="${SLURM_MEM:-8G}" --time="${SLURM_TIME:-01:00:00}" --output="$out/slurm/$log")
    [[ $tasks -gt 1 || $log == *%a* ]] && args+=(--array="1-$tasks")
    [[ -n $dep ]] && args+=(--dependency="afterok:$dep")
    local id
    id=$(sbatch --parsable "${args[@]}" --wrap="$cmd")
    echo "${id%%;*}"
}

id1=$(submit irsig-pass1 "$pass1" "" "pass1-%a.log" \
    "$qi thermal-scene $qs --state $qst --pass 1 --shard \${SLURM_ARRAY_TASK_ID}/$pass1 --threads $cpus --quiet$shared")
id2=$(submit irsig-pass2 "$pass2" "$id1" "pass2-%a.log" \
    "$qi thermal-scene $qs --state $qst --pass 2 --shard \${SLURM_ARRAY_TASK_ID}/$pass2 --threads $cpus --quiet$shared")
id3=$(submit irsig-tiles "$tiles" "$id2" "tile-%a.log" \
    "$qi render $qs -o $qo --state $qst --tile \${SLURM_ARRAY_TASK_ID}/$tiles --threads $cpus --quiet$extra")
id4=$(submit irsig-merge 1 "$id3" "merge.log" \
    "$qi merge $qo/*.tile*-of-$tiles.exr -o $qo --threads $cpus --quiet")

if [[ $local_run == 1 ]]; then
    echo "ran pass 1 ($pass1 shards), pass 2 ($pass2), $tiles tiles and the merge; outputs: $out"
else
    echo "submitted pass 1: job array $id1 (1-$pass1); pass 2: $id2 (1-$pass2, after pass 1);" \
        "tiles: $id3 (1-$tiles, after pass 2); merge: job $id4 (after all tiles)"
    echo "outputs: $out ; state: $state ; logs: $out/slurm/"
fi
