#!/usr/bin/env bash
# The default test suite under every OpenBLAS kernel this CPU can run and with 1 and 2 BLAS
# threads: the same verdicts and results on each (issue 16). Writes docs/results/blas_matrix.json
# (per run: kernel asked for, kernel loaded, threads, pytest's summary line, seconds, exit code)
# and exits non-zero if any run fails. Extra arguments go to pytest.
#   ./scripts/blas-matrix.sh            # about 4 x 3 + 2 x 3 minutes on a 2-core machine, warm cache
set -uo pipefail
cd "$(dirname "$0")/.."
source scripts/ensure-venv.sh
set +e
mkdir -p docs/results
log_dir=$(mktemp -d)
load_start=$(cut -d" " -f1-3 /proc/loadavg)
runs=()
failed=0

run_suite() {  # $1 label, $2 OPENBLAS_CORETYPE ("" = detected), $3 threads ("" = default)
    local label=$1 core=$2 threads=$3 loaded log start seconds code summary
    shift 3  # the rest: pytest's arguments
    log="$log_dir/$label.log"
    # A kernel the CPU cannot execute dies on its first BLAS call (illegal instruction): skip it.
    loaded=$(env ${core:+OPENBLAS_CORETYPE=$core} ${threads:+OPENBLAS_NUM_THREADS=$threads} .venv/bin/python -c "
import numpy as np, scipy.linalg, threadpoolctl
a = np.eye(8) + 0.1; scipy.linalg.lu_factor(a @ a)
print(','.join(sorted({i['architecture'] for i in threadpoolctl.threadpool_info()})))" 2>/dev/null)
    if [ -z "$loaded" ]; then
        echo "== $label: skipped, this CPU cannot run the $core kernel"
        runs+=("$label|$core||$threads|skipped: CPU cannot run this kernel|0|0")
        return
    fi
    echo "== $label (kernel ${core:-detected} -> $loaded, threads ${threads:-default})"
    start=$(date +%s)
    env ${core:+OPENBLAS_CORETYPE=$core} ${threads:+OPENBLAS_NUM_THREADS=$threads} \
        .venv/bin/python -m pytest -q -p no:cacheprovider "$@" > "$log" 2>&1
    code=$?
    seconds=$(( $(date +%s) - start ))
    summary=$(grep -E "^(=+ )?[0-9]+ (passed|failed)" "$log" | tail -1 | sed 's/=//g; s/^ *//; s/ *$//')
    echo "   $summary (${seconds} s, exit $code)"
    [ "$code" -ne 0 ] && { failed=1; tail -30 "$log"; }
    runs+=("$label|$core|$loaded|$threads|$summary|$seconds|$code")
}

for core in Haswell Zen Sandybridge Prescott; do
    run_suite "$core" "$core" "" "$@"
done
for threads in 1 2; do
    run_suite "threads-$threads" "" "$threads" "$@"
done

printf '%s\n' "${runs[@]}" | PYTEST_ARGS="$*" LOAD_START="$load_start" .venv/bin/python -c "
import json, os, sys
from ffrf.output.provenance import provenance
rows = []
for line in sys.stdin.read().splitlines():
    label, core, loaded, threads, summary, seconds, code = line.split('|')
    rows.append(dict(label=label, coretype=core or 'detected', loaded_kernel=loaded, blas_threads=threads or 'default',
                     pytest=summary, seconds=int(seconds), exit_code=int(code)))
command = ' '.join(['./scripts/blas-matrix.sh', os.environ['PYTEST_ARGS']]).strip()
meta = provenance(command, load_at_start=[float(x) for x in os.environ['LOAD_START'].split()])
json.dump(dict(meta=meta, results=dict(runs=rows)), open('docs/results/blas_matrix.json', 'w'), indent=1)
print('wrote docs/results/blas_matrix.json')
"
exit $failed
