"""Per-kernel numba compile times of ``python -m ffrf warmup`` run cold (issue #22).

The command runs in a fresh process with numba's cache in an empty folder, under a listener on numba's
``"numba:compile"`` events (``numba.core.event``). Each compilation is recorded with its inclusive time
(the kernels it compiles on the way included) and its own time (those excluded); a kernel compiled more than
once (one specialisation per argument types, e.g. a ``Literal[bool]`` flag) lists every compilation. At the
end the process lists every kernel that holds a compiled or cached specialisation, so ``--command bennett``
on the warmed cache (``--keep-cache``) shows which kernels the main job calls from Python (kernels they
call, loaded with them from the cache, are not listed).

Usage::

    .venv/bin/python -m bench compile_times --json out/compile_times.json
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench import ROOT
from bench.report import write_report

COMMANDS = {
    "warmup": ["warmup"],
    "bennett": ["bennett", "--variant", "pla", "--out", "{out}"],
}


def _kernel_name(dispatcher) -> str:
    return f"{dispatcher.py_func.__module__}.{dispatcher.py_func.__qualname__}"


def _child(command: list[str], out: Path) -> None:
    """Run ``python -m ffrf COMMAND`` in this process with a compile listener; write the records to ``out``."""
    from numba.core import event
    from numba.core.registry import CPUDispatcher

    from ffrf.cli import main

    records: list[dict] = []
    stack: list[list] = []  # [name, literal args, start, time of nested compilations, own time in LLVM]

    class Recorder(event.Listener):
        def on_start(self, ev):
            args = [str(a) for a in ev.data["args"] if "Literal" in str(a)]
            stack.append([_kernel_name(ev.data["dispatcher"]), args, time.perf_counter(), 0.0, 0.0])

        def on_end(self, ev):
            name, literals, started, nested, llvm = stack.pop()
            inclusive = time.perf_counter() - started
            if stack:
                stack[-1][3] += inclusive
            record = {"kernel": name, "inclusive_s": inclusive, "own_s": inclusive - nested, "llvm_s": llvm}
            records.append(dict(record, literals=literals, top_level=not stack))

    class LLVMTimer(event.Listener):  # LLVM's share of a kernel's own time (optimisation and code generation)
        def on_start(self, ev):
            self.started = time.perf_counter()

        def on_end(self, ev):
            if stack:
                stack[-1][4] += time.perf_counter() - self.started

    started = time.perf_counter()
    with event.install_listener("numba:compile", Recorder()), event.install_listener("numba:llvm_lock", LLVMTimer()):
        status = main(command)
    wall = time.perf_counter() - started
    import gc

    used = sorted({_kernel_name(d) for d in gc.get_objects() if isinstance(d, CPUDispatcher) and d.signatures})
    out.write_text(json.dumps({"status": status, "wall_s": wall, "compilations": records, "kernels_used": used}))


def _summary(records: list[dict]) -> list[dict]:
    """Per kernel: number of compilations, summed inclusive, own and own LLVM times (s), slowest first."""
    kernels: dict[str, dict] = {}
    for r in records:
        k = kernels.setdefault(r["kernel"], {"kernel": r["kernel"], "compilations": 0})
        k["compilations"] += 1
        for key in ("inclusive_s", "own_s", "llvm_s"):
            k[key] = round(k.get(key, 0.0) + r[key], 2)
    return sorted(kernels.values(), key=lambda k: -k["inclusive_s"])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, required=True)
    parser.add_argument("--command", choices=sorted(COMMANDS), default="warmup")
    parser.add_argument("--keep-cache", type=Path, help="numba cache folder to use and keep (default: a fresh one)")
    parser.add_argument("--child", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        command = [part.format(out=Path(folder) / "out") for part in COMMANDS[args.command]]
        if args.child:
            _child(command, args.child)
            return 0
        cache = args.keep_cache or Path(folder) / "cache"
        raw = Path(folder) / "raw.json"
        env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), PYTHONPATH=str(ROOT))
        child = [
            sys.executable,
            "-m",
            "bench.compile_times",
            "--json",
            str(args.json),
            "--command",
            args.command,
            "--child",
            str(raw),
        ]
        started = time.perf_counter()
        subprocess.run(child, cwd=ROOT, env=env, check=True, stdout=subprocess.DEVNULL)
        process_s = time.perf_counter() - started
        data = json.loads(raw.read_text())
    report = {
        "command": f"python -m ffrf {' '.join(COMMANDS[args.command])}",
        "process_s": round(process_s, 1),
        "command_s": round(data["wall_s"], 1),
        "compile_s": round(sum(r["own_s"] for r in data["compilations"]), 1),
        "llvm_s": round(sum(r["llvm_s"] for r in data["compilations"]), 1),
        "kernels": _summary(data["compilations"]),
        "literal_specialisations": sorted(
            {f"{r['kernel']}{r['literals']}" for r in data["compilations"] if r["literals"]}
        ),
        "top_level_compiled": sorted({r["kernel"] for r in data["compilations"] if r["top_level"]}),
        "kernels_used": data["kernels_used"],
        "cpu_count": os.cpu_count(),
    }
    write_report(report, args.json, echo=False)
    print(json.dumps({k: report[k] for k in ("process_s", "command_s", "compile_s", "llvm_s")}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
