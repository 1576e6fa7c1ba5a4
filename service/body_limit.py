"""Refuse request bodies over MPM_MAX_BODY_BYTES with 413, before they are read whole.

A declared Content-Length over the limit is answered at once; a chunked body is
counted as it arrives and cut off when it passes the limit.
"""
from __future__ import annotations

from starlette.types import ASGIApp, Message, Receive, Scope, Send

from service.errors import error_response


class BodySizeLimit:
    def __init__(self, app: ASGIApp, max_bytes: int):
        self.app, self.max_bytes = app, max_bytes

    def _too_large(self):
        return error_response(413, "request_too_large",
                              f"the request body is over the limit of {self.max_bytes} bytes",
                              {"limit": "MPM_MAX_BODY_BYTES", "max_bytes": self.max_bytes})

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        length = dict(scope["headers"]).get(b"content-length")
        if length is not None and length.isdigit() and int(length) > self.max_bytes:
            return await self._too_large()(scope, receive, send)

        received = 0
        over = False
        answered = False

        async def counting_receive() -> Message:
            nonlocal received, over
            message = await receive()
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received > self.max_bytes:
                    over = True
                    return {"type": "http.disconnect"}  # the app stops reading
            return message

        async def guarded_send(message: Message) -> None:
            nonlocal answered
            if over:  # whatever the app says about the cut-off body, the answer is 413
                if not answered:
                    answered = True
                    await self._too_large()(scope, receive, send)
                return
            await send(message)

        await self.app(scope, counting_receive, guarded_send)
        if over and not answered:
            await self._too_large()(scope, receive, send)
