"""ASGI middleware: the request body size limit (413 as a problem document), a body in a
content coding refused (415), every error a problem document, HEAD answered as GET without
its body."""

from __future__ import annotations

import json

from starlette.exceptions import HTTPException
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from service.errors import PROBLEM_JSON, instance_of


class BodyLimitMiddleware:
    """Refuse bodies over ``max_bytes`` (over ``per_path[path]`` on the paths it names: a
    lab's measured data set is larger than any other request): by Content-Length before
    reading, and while reading a body without one (chunked)."""

    def __init__(self, app: ASGIApp, max_bytes: int,
                 per_path: dict[str, int] | None = None) -> None:
        self.app = app
        self.max_bytes = max_bytes
        self.per_path = dict(per_path or {})

    @staticmethod
    def _message(limit: int) -> str:
        return f"the request body exceeds the limit of {limit} bytes"

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        limit = self.per_path.get(str(scope.get("path", "")).rstrip("/"), self.max_bytes)
        headers = dict(scope.get("headers") or [])
        length = headers.get(b"content-length")
        if length is not None:
            try:
                too_large = int(length) > limit
            except ValueError:
                too_large = False
            if too_large:
                await self._refuse(scope, send, limit)
                return
        received = 0

        async def limited() -> Message:
            nonlocal received
            message = await receive()
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received > limit:
                    raise HTTPException(413, self._message(limit))
            return message

        await self.app(scope, limited, send)

    async def _refuse(self, scope: Scope, send: Send, limit: int) -> None:
        await _send_json(send, 413, {"type": "urn:balloon:problem:payload-too-large",
                                     "title": "Request body too large", "status": 413,
                                     "detail": self._message(limit),
                                     "instance": instance_of(scope.get("path", ""))},
                         [(b"connection", b"close")])


class _HttpMiddleware:
    """An ASGI middleware that acts on HTTP requests only (``http``); the rest pass."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        await self.http(scope, receive, send)

    async def http(self, scope: Scope, receive: Receive, send: Send) -> None:
        raise NotImplementedError


ACCEPTED_ENCODING = "identity"


class IdentityBodyMiddleware(_HttpMiddleware):
    """Refuse a request whose body comes in a content coding (``Content-Encoding: gzip``,
    ``deflate``, ``br``...) with 415 and ``Accept-Encoding: identity`` (RFC 9110 15.5.16):
    the bodies are small JSON (64 KiB; a lab's data set 4 MiB), so compression saves the
    client little, and decoding one would let a few KiB expand past the body limit before
    any check could count it (a decompression bomb). Read as JSON it was a 422 "cannot be
    parsed as JSON", which never said why."""

    async def http(self, scope: Scope, receive: Receive, send: Send) -> None:
        headers = scope.get("headers") or []
        codings = [value.decode("latin-1").strip().lower()
                   for name, value in headers if name == b"content-encoding"]
        sent = [c.strip() for value in codings for c in value.split(",") if c.strip()]
        if all(c == ACCEPTED_ENCODING for c in sent) or not _has_body(headers):
            await self.app(scope, receive, send)
            return
        shown = ", ".join(sent)[:60]
        detail = (f"the request body came with Content-Encoding {shown!r}; send it "
                  f"uncompressed (Content-Encoding absent or {ACCEPTED_ENCODING})")
        await _send_json(send, 415, {
            "type": "urn:balloon:problem:unsupported-media-type",
            "title": "Unsupported Media Type", "status": 415, "detail": detail,
            "instance": instance_of(scope.get("path", "")),
            "errors": [{"loc": ["header", "content-encoding"], "field": "Content-Encoding",
                        "message": f"{shown!r} is not accepted",
                        "allowed": ACCEPTED_ENCODING}]},
            [(b"accept-encoding", ACCEPTED_ENCODING.encode())])


def _has_body(headers: list[tuple[bytes, bytes]]) -> bool:
    """The request carries a body: a Content-Length above 0, or a Transfer-Encoding."""
    for name, value in headers:
        if name == b"transfer-encoding" or (name == b"content-length"
                                            and value.strip() not in (b"", b"0")):
            return True
    return False


async def _send_json(send: Send, status: int, problem: dict,
                     headers: list[tuple[bytes, bytes]]) -> None:
    """Send ``problem`` as the whole answer, ``application/problem+json``."""
    body = json.dumps(problem).encode()
    await send({"type": "http.response.start", "status": status,
                "headers": [*headers, (b"content-type", PROBLEM_JSON.encode()),
                            (b"content-length", str(len(body)).encode())]})
    await send({"type": "http.response.body", "body": body})


class ProblemOnlyMiddleware(_HttpMiddleware):
    """Every error answer a problem document: the few that Starlette writes itself in
    text/plain (a file's Range header it cannot serve: 400, 416 with Content-Range) are
    rewritten as ``application/problem+json`` with their status and words."""

    async def http(self, scope: Scope, receive: Receive, send: Send) -> None:
        held: dict[str, Message] = {}
        chunks: list[bytes] = []

        async def send_problem(message: Message) -> None:
            if message["type"] == "http.response.start" and _plain_error(message):
                held["start"] = message
                return
            if "start" not in held:
                await send(message)
                return
            chunks.append(message.get("body", b""))
            if not message.get("more_body", False):
                await _send_problem(send, held["start"], b"".join(chunks), scope)

        await self.app(scope, receive, send_problem)


def _plain_error(start: Message) -> bool:
    """An error status whose body is not a problem document."""
    headers = dict(start.get("headers") or [])
    content_type = headers.get(b"content-type", b"").decode("latin-1")
    return start["status"] >= 400 and not content_type.startswith(PROBLEM_JSON)


async def _send_problem(send: Send, start: Message, text: bytes, scope: Scope) -> None:
    from http import HTTPStatus

    status = start["status"]
    phrase = HTTPStatus(status).phrase if status in HTTPStatus._value2member_map_ else "Error"
    detail = text.decode("utf-8", "replace").strip()[:200] or phrase
    kept = [(k, v) for k, v in start.get("headers") or []
            if k.lower() not in (b"content-type", b"content-length")]
    await _send_json(send, status, {"type": f"urn:balloon:problem:http-{status}",
                                    "title": phrase, "status": status, "detail": detail,
                                    "instance": instance_of(scope.get("path", ""))}, kept)


class HeadAsGetMiddleware(_HttpMiddleware):
    """``HEAD`` answered as ``GET`` without its body (RFC 9110 9.3.2: the same status and
    headers, Content-Length included): FastAPI's GET routes do not take HEAD, and a
    monitor probing ``HEAD /v1/health`` got 405. A path without GET still answers 405."""

    async def http(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["method"] != "HEAD":
            await self.app(scope, receive, send)
            return

        async def without_body(message: Message) -> None:
            if message["type"] == "http.response.body":
                message = {**message, "body": b""}
            await send(message)

        await self.app({**scope, "method": "GET"}, receive, without_body)
