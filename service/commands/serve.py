"""``balloon serve [--host HOST] [--port PORT]``: run the REST service with uvicorn.

Settings come from the environment (``BALLOON_*``, see ``service.settings``); the
fitted surrogate is loaded once at start-up.
"""

from __future__ import annotations

import argparse
import errno
import socket

from service.commands.numbers import checked_int, int_action

PORTS = (1, 65535)   # a TCP port, lo <= port <= hi


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "serve", help="run the REST service (uvicorn)",
        description="Run the design service. Configure it with BALLOON_* environment "
                    "variables (BALLOON_DB_PATH, BALLOON_SURROGATE_PATH, BALLOON_API_KEY, ...); "
                    "see docs/service.md.")
    parser.add_argument("--host", default="127.0.0.1",
                        help="interface to listen on (default 127.0.0.1; 0.0.0.0 for all)")
    int_action(parser.add_argument("--port", type=int, default=8000,
                                   help="TCP port (default 8000)"), "port", *PORTS)
    parser.add_argument("--log-level", default="info",
                        choices=("critical", "error", "warning", "info", "debug"),
                        help="what the server logs to stderr: info (default) a line per "
                             "request, warning and above only problems, debug everything")
    parser.set_defaults(func=run)


def check_address(host: str, port: int) -> None:
    """Bind ``host``:``port`` once, as uvicorn will, before the models load (~10 s):
    a host that does not resolve or is not this machine's is an InputError naming
    --host, a port in use or not ours to take one naming --port; one line, no log."""
    from solver.errors import InputError

    family = socket.AF_INET6 if ":" in host else socket.AF_INET  # uvicorn's own choice
    try:
        with socket.socket(family, socket.SOCK_STREAM) as sock:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind((host, port))
    except (socket.gaierror, UnicodeError):
        raise InputError("--host", f"{host!r} does not resolve to an address",
                         "an address or name of this machine, e.g. 127.0.0.1 or 0.0.0.0"
                         ) from None
    except OSError as exc:
        if exc.errno in (errno.EADDRINUSE, errno.EACCES):
            raise InputError("--port", f"cannot listen on {host}:{port} "
                             f"({exc.strerror})", f"a free port, {PORTS[0]}-{PORTS[1]}; below 1024 "
                             "needs privileges") from None
        raise InputError("--host", f"cannot listen on {host}:{port} ({exc.strerror})",
                         "an address of this machine, e.g. 127.0.0.1 or 0.0.0.0") from None


def run(args: argparse.Namespace) -> int:

    checked_int("--port", args.port, "port", *PORTS)
    check_address(args.host, args.port)   # before the imports and the models' loading
    import uvicorn

    from service.app import create_app
    from service.settings import get_settings

    app = create_app(get_settings())
    uvicorn.run(app, host=args.host, port=args.port, log_level=args.log_level,
                **server_options())
    return 0


def server_options() -> dict[str, object]:
    """uvicorn's options of ``balloon serve`` beside the address: the client's address
    from a proxy's headers, and uvicorn's own 400 (a request it cannot read as HTTP/1.1)
    a problem document too (``service.unreadable_request``)."""
    from service.unreadable_request import ProblemH11Protocol

    return {"proxy_headers": True, "http": ProblemH11Protocol}
