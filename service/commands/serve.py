"""``balloon serve [--host HOST] [--port PORT]``: run the REST service with uvicorn.

Settings come from the environment (``BALLOON_*``, see ``service.settings``); the
fitted surrogate is loaded once at start-up.
"""

from __future__ import annotations

import argparse


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "serve", help="run the REST service (uvicorn)",
        description="Run the design service. Configure it with BALLOON_* environment "
                    "variables (BALLOON_DB_PATH, BALLOON_SURROGATE_PATH, BALLOON_API_KEY, ...); "
                    "see docs/service.md.")
    parser.add_argument("--host", default="127.0.0.1",
                        help="interface to listen on (default 127.0.0.1; 0.0.0.0 for all)")
    parser.add_argument("--port", type=int, default=8000, help="TCP port (default 8000)")
    parser.add_argument("--log-level", default="info",
                        choices=("critical", "error", "warning", "info", "debug"))
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import uvicorn

    from service.app import create_app
    from service.settings import get_settings
    from solver.errors import InputError

    if not 0 < args.port < 65536:
        raise InputError("--port", f"got {args.port}", "1 <= port <= 65535")
    app = create_app(get_settings())
    uvicorn.run(app, host=args.host, port=args.port, log_level=args.log_level,
                proxy_headers=True)
    return 0
