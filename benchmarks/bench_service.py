"""Load test of the REST service on loopback: POST /v1/predict against GET /v1/health.

Starts `balloon serve` (one uvicorn process) on 127.0.0.1 with its default settings,
i.e. the shipped data (service/data/surrogate.json and curves.h5; the paper's preset
when the package has no shipped surrogate), then drives it with an async httpx client:
``--concurrency`` requests in flight, alternating phases of each endpoint (so drift on a
shared machine hits both alike), ``--duration`` seconds per endpoint in total. Reports throughput
(requests/s) and latency percentiles (ms) per endpoint, and checks the targets:
predict throughput >= 70 % of health's, predict p99 < 20 ms.

    .venv/bin/python benchmarks/bench_service.py [--duration 20] [--concurrency 2]

``--without refuse_unheld_numbers`` (or another of the app's request-wide dependencies,
``DEPENDENCIES``) measures what one costs instead: a second server whose app has it
replaced by an async no-op, and POST /v1/predict on the two in alternating phases; it
reports their throughputs and the ratio, without / with.

The client runs on the same machine and competes for its cores: the figures are a
lower bound of what the server does alone.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import platform
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import httpx
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
LAUNCH = ("import argparse, os, sys; from service.commands import serve; import service.app; "
          "exec(os.environ.get('BENCH_WITHOUT', '')); "
          "p = argparse.ArgumentParser(prog='balloon'); serve.register(p.add_subparsers()); "
          "a = p.parse_args(sys.argv[1:]); sys.exit(a.func(a))")
#: the app's request-wide dependencies (service.app.create_app) --without can replace
DEPENDENCIES = ("refuse_repeated_fields", "refuse_unread_query", "refuse_unheld_numbers")
NO_OP = "async def _no_op() -> None:\n    return None\nservice.app.{name} = _no_op\n"
PREDICT = {"design": {"L_mm": 7.1, "t_mm": 0.5},
           "pressures_pa": [0, 250, 500, 750, 1000, 1250, 1500, 1750, 2000, 2250]}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_server(tmp: Path, without: str | None = None) -> tuple[subprocess.Popen, str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT),
           "BENCH_WITHOUT": NO_OP.format(name=without) if without else ""}
    if not (ROOT / "service" / "data" / "surrogate.json").is_file():
        from surrogate import paper_surrogate, save_surrogate

        save_surrogate(paper_surrogate(), tmp / "surrogate.json")
        env["BALLOON_SURROGATE_PATH"] = str(tmp / "surrogate.json")
    port = free_port()
    proc = subprocess.Popen([sys.executable, "-c", LAUNCH, "serve", "--host", "127.0.0.1",
                             "--port", str(port), "--log-level", "warning"], env=env)
    url = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        try:
            if httpx.get(f"{url}/v1/health", timeout=1).json()["surrogate"]["loaded"]:
                return proc, url
        except httpx.HTTPError:
            time.sleep(0.2)
    proc.kill()
    raise SystemExit("the server did not start")


async def phase(client: httpx.AsyncClient, kind: str, seconds: float, concurrency: int
                ) -> tuple[list[float], int]:
    """Run ``concurrency`` loops for ``seconds``; latencies (s) and error count."""
    latencies: list[float] = []
    errors = 0
    stop = time.perf_counter() + seconds

    async def loop() -> None:
        nonlocal errors
        while time.perf_counter() < stop:
            t0 = time.perf_counter()
            if kind == "predict":
                r = await client.post("/v1/predict", json=PREDICT)
            else:
                r = await client.get("/v1/health")
            latencies.append(time.perf_counter() - t0)
            errors += r.status_code != 200

    await asyncio.gather(*(loop() for _ in range(concurrency)))
    return latencies, errors


async def drive(urls: dict[str, tuple[str, str]], duration: float, concurrency: int,
                rounds: int) -> dict:
    """Alternating phases of each entry of ``urls`` (name -> server url, endpoint kind)."""
    limits = httpx.Limits(max_connections=concurrency, max_keepalive_connections=concurrency)
    out: dict[str, dict] = {k: {"lat": [], "errors": 0, "time": 0.0} for k in urls}
    clients = {k: httpx.AsyncClient(base_url=url, limits=limits, timeout=10)
               for k, (url, _) in urls.items()}
    try:
        for name, (_, kind) in urls.items():  # warm-up
            await phase(clients[name], kind, 1.0, concurrency)
        for _ in range(rounds):
            for name, (_, kind) in urls.items():
                t0 = time.perf_counter()
                lat, err = await phase(clients[name], kind, duration / rounds, concurrency)
                out[name]["time"] += time.perf_counter() - t0
                out[name]["lat"] += lat
                out[name]["errors"] += err
    finally:
        for client in clients.values():
            await client.aclose()
    result = {}
    for kind, d in out.items():
        lat = np.asarray(d["lat"]) * 1e3
        result[kind] = {"requests": int(lat.size), "errors": d["errors"],
                        "throughput_rps": lat.size / d["time"],
                        "p50_ms": float(np.percentile(lat, 50)),
                        "p99_ms": float(np.percentile(lat, 99))}
    return result


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=20.0, help="seconds per endpoint")
    parser.add_argument("--concurrency", type=int, default=2, help="requests in flight")
    parser.add_argument("--rounds", type=int, default=4, help="alternating phases")
    parser.add_argument("--without", choices=DEPENDENCIES,
                        help="measure this dependency's cost to POST /v1/predict instead")
    args = parser.parse_args()
    if args.without:
        return compare_without(args)
    with tempfile.TemporaryDirectory() as tmp:
        proc, url = start_server(Path(tmp))
        try:
            result = asyncio.run(drive({"health": (url, "health"), "predict": (url, "predict")},
                                       args.duration, args.concurrency, args.rounds))
        finally:
            proc.terminate()
            proc.wait(10)
    ratio = result["predict"]["throughput_rps"] / result["health"]["throughput_rps"]
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.1f}; python {platform.python_version()}")
    print(f"concurrency {args.concurrency}, {args.duration:g} s per endpoint, "
          f"{len(PREDICT['pressures_pa'])} pressures per predict")
    print_table("endpoint", result)
    ok_ratio = ratio >= 0.70
    ok_p99 = result["predict"]["p99_ms"] < 20.0
    print(f"predict / health throughput: {ratio:.2f} (target >= 0.70: "
          f"{'met' if ok_ratio else 'NOT met'}); predict p99 "
          f"{result['predict']['p99_ms']:.2f} ms (target < 20 ms: "
          f"{'met' if ok_p99 else 'NOT met'})")
    print(json.dumps({"ratio": ratio, **result}))
    return 0 if ok_ratio and ok_p99 else 1


def print_table(first: str, result: dict[str, dict]) -> None:
    """``result`` (name -> figures) as a Markdown table."""
    print(f"| {first} | requests | errors | throughput (req/s) | p50 (ms) | p99 (ms) |")
    print("|---|---|---|---|---|---|")
    for name, r in result.items():
        print(f"| {name} | {r['requests']} | {r['errors']} | {r['throughput_rps']:.0f} | "
              f"{r['p50_ms']:.2f} | {r['p99_ms']:.2f} |")


def compare_without(args: argparse.Namespace) -> int:
    """POST /v1/predict on the app as served and on one without ``args.without``."""
    with tempfile.TemporaryDirectory() as tmp:
        proc, url = start_server(Path(tmp))
        try:
            bare, bare_url = start_server(Path(tmp), args.without)
            try:
                result = asyncio.run(drive({"with": (url, "predict"),
                                            "without": (bare_url, "predict")},
                                           args.duration, args.concurrency, args.rounds))
            finally:
                bare.terminate()
                bare.wait(10)
        finally:
            proc.terminate()
            proc.wait(10)
    ratio = result["without"]["throughput_rps"] / result["with"]["throughput_rps"]
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load average {os.getloadavg()[0]:.1f}; concurrency {args.concurrency}, "
          f"{args.duration:g} s per server")
    print_table(f"POST /v1/predict, {args.without}", result)
    print(f"throughput without / with: {ratio:.3f}")
    print(json.dumps({"ratio": ratio, **result}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
