"""Start-up of the quick commands and throughput of the ordering service.

Targets (issue 14), as medians of whole-process wall times on this 2-core machine:
- `cramlite order FILE` on a 5-item request <= 120 ms (a bare `python -c pass` ~25 ms)
- `cramlite strategies` and `cramlite --help`: import no numpy, simulator or Dask
- `cramlite order --serve`: 1,000 requests of 5 items through the pipe < 1 s, start-up
  included; also timed with a client that writes one line and waits for its reply.

Run: .venv/bin/python benchmarks/bench_startup.py [--runs 15]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BIN = Path(sys.executable).parent
CRAMLITE = [str(BIN / "cramlite")] if (BIN / "cramlite").exists() else \
    [sys.executable, "-m", "cramlite"]
#: v1's items seen from the robot's start: no ties, so no random generator is needed.
REQUEST = {"robot": [-0.5, -1.8, 0.0], "params": {"mid_k": 0.3, "c": 1.7}, "items": [
    {"name": "spoon", "position": [1.45, 0.35, 0.85]},
    {"name": "breakfast-cereal", "position": [-0.85, 1.75, 0.86]},
    {"name": "milk", "position": [1.45, -0.15, 0.85]},
    {"name": "cup", "position": [1.45, 0.85, 0.85]},
    {"name": "bowl", "position": [1.45, -0.65, 0.85], "category": "mid"}]}


def wall(command: list[str], stdin: bytes = b"") -> float:
    start = time.perf_counter()
    result = subprocess.run(command, input=stdin, capture_output=True)
    elapsed = time.perf_counter() - start
    if result.returncode != 0:
        raise SystemExit(f"{command} failed: {result.stderr.decode()[-500:]}")
    return elapsed


def lockstep(requests: int) -> float:
    """A client that writes one request and reads its reply before the next."""
    start = time.perf_counter()
    service = subprocess.Popen([*CRAMLITE, "order", "--serve"], stdin=subprocess.PIPE,
                               stdout=subprocess.PIPE, bufsize=0)
    line = (json.dumps(REQUEST) + "\n").encode()
    for _ in range(requests):
        service.stdin.write(line)
        if not service.stdout.readline():
            raise SystemExit("the service stopped answering")
    service.stdin.close()
    service.wait()
    return time.perf_counter() - start


def report(label: str, times: list[float], target: str = "") -> None:
    ms = [t * 1000 for t in times]
    print(f"{label:<44} median {statistics.median(ms):7.1f} ms  (min {min(ms):.1f}, max "
          f"{max(ms):.1f}, n={len(ms)}){'  target ' + target if target else ''}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=15)
    args = parser.parse_args()
    print(f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.2f} (the machine may "
          "be shared: compare medians)")
    with tempfile.TemporaryDirectory() as folder:
        request = Path(folder) / "request.json"
        request.write_text(json.dumps(REQUEST))
        many = ((json.dumps(REQUEST) + "\n") * 1000).encode()
        cases = [
            ("python -c pass", [sys.executable, "-c", "pass"], b"", ""),
            ("cramlite --help", [*CRAMLITE, "--help"], b"", ""),
            ("cramlite strategies", [*CRAMLITE, "strategies"], b"", ""),
            ("cramlite order FILE (5 items)", [*CRAMLITE, "order", str(request)], b"",
             "<= 120 ms"),
            ("cramlite order --serve, 1,000 requests", [*CRAMLITE, "order", "--serve"], many,
             "< 1000 ms"),
        ]
        for label, command, stdin, target in cases:
            wall(command, stdin)  # warm the file cache
            report(label, [wall(command, stdin) for _ in range(args.runs)], target)
        runs = max(3, args.runs // 3)
        report("order --serve, 1,000 lock-step round trips", [lockstep(1000)
                                                              for _ in range(runs)])


if __name__ == "__main__":
    main()
