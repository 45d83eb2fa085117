"""The explorer in a real browser on loopback: first render and slider move -> redrawn curve.

Starts `balloon serve` on 127.0.0.1 (the shipped data; bench_service.start_server) and
headless Debian Chromium driven by Playwright, then measures in the page (performance.now):

* first render: navigation start -> the first curve drawn (``window.explorer.firstRenderMs``:
  HTML, CSS, the ES modules, GET /v1/materials and POST /v1/predict, the SVG), each load in
  a fresh browser context (empty cache), ``--loads`` times;
* slider move: the L slider's input event -> curve redrawn with the new prediction
  (``window.explorer.timings``: the 16 ms debounce, the request, the redraw), one arrow key
  at a time, ``--moves`` times; and interleaved with it, in the same page, a bare
  ``fetch('/v1/predict')`` of the same body, so that the page's own share is a ratio of two
  things measured in one run.

Targets: first render < 1 s, slider move < 100 ms (median and 95th percentile reported).

    .venv/bin/python benchmarks/bench_explorer.py [--loads 10] [--moves 40]
"""

from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_service import start_server  # noqa: E402

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]
BARE_FETCH = """async () => {
  const body = JSON.stringify(window.explorer.request);
  const t0 = performance.now();
  const headers = {'Content-Type': 'application/json'};
  const r = await fetch('/v1/predict', {method: 'POST', body, headers});
  await r.json();
  return performance.now() - t0;
}"""


def stats(values: list[float]) -> dict[str, float]:
    a = np.asarray(values, float)
    return {"n": int(a.size), "median_ms": float(np.median(a)),
            "p95_ms": float(np.percentile(a, 95)), "max_ms": float(a.max())}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--loads", type=int, default=10)
    ap.add_argument("--moves", type=int, default=40)
    args = ap.parse_args()
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as tmp:
        proc, url = start_server(Path(tmp))
        try:
            with sync_playwright() as pw:
                browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
                first = []
                for _ in range(args.loads):
                    ctx = browser.new_context(viewport={"width": 1280, "height": 900})
                    page = ctx.new_page()
                    page.goto(url + "/")
                    page.wait_for_selector("body[data-ready=true]")
                    first.append(page.evaluate("window.explorer.firstRenderMs"))
                    ctx.close()
                ctx = browser.new_context(viewport={"width": 1280, "height": 900})
                page = ctx.new_page()
                page.goto(url + "/")
                page.wait_for_selector("body[data-ready=true]")
                page.focus("#L_mm-range")
                bare = []
                for k in range(args.moves):
                    n = page.evaluate("window.explorer.timings.length")
                    page.keyboard.press("ArrowRight" if (k // 20) % 2 == 0 else "ArrowLeft")
                    page.wait_for_function(f"window.explorer.timings.length > {n}")
                    page.wait_for_timeout(50)  # the nearest-FE follow-up settles
                    bare.append(page.evaluate(BARE_FETCH))
                    page.focus("#L_mm-range")
                moves = page.evaluate("window.explorer.timings")
                version = browser.version
                browser.close()
        finally:
            proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:  # a server slow to shut down loses no figures
                proc.kill()
                proc.wait()
    out = {"machine": f"{platform.machine()} {platform.processor() or ''}".strip(),
           "chromium": version, "first_render": stats(first), "slider_move": stats(moves),
           "bare_predict_fetch": stats(bare)}
    out["slider_over_bare_fetch"] = (out["slider_move"]["median_ms"]
                                     / out["bare_predict_fetch"]["median_ms"])
    print(json.dumps(out, indent=1))
    ok = out["first_render"]["median_ms"] < 1000 and out["slider_move"]["median_ms"] < 100
    print("targets (first render < 1 s, slider move < 100 ms, medians):",
          "met" if ok else "NOT met")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
