"""A request the server cannot read as HTTP/1.1 answered as an RFC 9457 problem.

uvicorn (h11) refuses a request whose head it cannot parse -- malformed, or a request line
and headers longer than h11 buffers while they arrive (``HEAD_BYTES``: a 1 MB URL, a query
of 20,000 parameters, a 300 kB header; whether a head between 16 and ~100 kB is read
depends on how its bytes arrive) -- with its own ``400`` in ``text/plain``, before the app
sees it. ``balloon serve`` runs uvicorn with ``ProblemH11Protocol``, whose 400 is
``application/problem+json`` like every other error of the service. It has no
``instance``: the request's path was not read.
"""

from __future__ import annotations

import json

import h11
from h11._connection import DEFAULT_MAX_INCOMPLETE_EVENT_SIZE  # as uvicorn imports it
from uvicorn.protocols.http.h11_impl import H11Protocol

from service.errors import PROBLEM_JSON

#: what h11 buffers of a request's head while it arrives (h11's default, uvicorn's too)
HEAD_BYTES = DEFAULT_MAX_INCOMPLETE_EVENT_SIZE

UNREADABLE = {
    "type": "urn:balloon:problem:http-400", "title": "Bad Request", "status": 400,
    "detail": "the request could not be read as HTTP/1.1: malformed, or its request line "
              f"and headers longer than {HEAD_BYTES} bytes (allowed: a URL and headers "
              "of a few kB; large inputs go in a POST body)"}


class ProblemH11Protocol(H11Protocol):
    """uvicorn's h11 protocol, its own 400 a problem document."""

    def send_400_response(self, msg: str) -> None:
        body = json.dumps(UNREADABLE).encode()
        headers = [(b"content-type", PROBLEM_JSON.encode()),
                   (b"content-length", str(len(body)).encode()), (b"connection", b"close")]
        for event in (h11.Response(status_code=400, headers=headers, reason=b"Bad Request"),
                      h11.Data(data=body), h11.EndOfMessage()):
            self.transport.write(self.conn.send(event))
        self.transport.close()
