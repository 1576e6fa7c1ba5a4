"""API tokens: who is calling. With MPM_API_TOKENS set, every `/v1` request needs
`Authorization: Bearer <token>`; the token names its owner, and the routes show a
caller only its own jobs. Without tokens nobody is identified (a local, single-user
service: `mpm serve` then listens on 127.0.0.1 unless told otherwise).

MPM_API_TOKENS is `owner:token,owner:token,...` or `@/path/to/file` (one
`owner:token` a line; blank lines and `#` comments ignored). An owner may have
several tokens (to rotate them). Tokens are compared in constant time and never
logged, echoed or put in a URL.
"""
from __future__ import annotations

import hashlib
import hmac
import re
from pathlib import Path

from fastapi import Request, Security
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer
from starlette.types import ASGIApp, Receive, Scope, Send

from service.errors import ApiError, error_response

OWNER = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")
MIN_TOKEN_LENGTH = 16
_UNAUTHORIZED_HEADERS = {"WWW-Authenticate": 'Bearer realm="mpm"'}


class TokenError(ValueError):
    """MPM_API_TOKENS cannot be read; the message never contains a token."""


def _digest(token: str) -> bytes:
    # Comparing fixed-length digests: compare_digest then takes the same time whatever the length.
    return hashlib.sha256(token.encode()).digest()


class Tokens:
    """The configured tokens, by digest, each with its owner."""

    def __init__(self, pairs: list[tuple[str, str]]):
        self._entries: list[tuple[bytes, str]] = []
        seen: set[bytes] = set()
        for number, (owner, token) in enumerate(pairs, start=1):
            where = f"MPM_API_TOKENS entry {number}"
            if not OWNER.match(owner):
                raise TokenError(f"{where}: the owner must be 1-64 letters, digits, '.', '_' or '-' "
                                 "(starting with a letter or digit)")
            if len(token) < MIN_TOKEN_LENGTH or any(c.isspace() for c in token):
                raise TokenError(f"{where} (owner {owner}): the token must be at least "
                                 f"{MIN_TOKEN_LENGTH} characters without blanks")
            digest = _digest(token)
            if digest in seen:
                raise TokenError(f"{where} (owner {owner}): the same token is given twice")
            seen.add(digest)
            self._entries.append((digest, owner))
        if not self._entries:
            raise TokenError("MPM_API_TOKENS is set but names no token")

    @property
    def owners(self) -> set[str]:
        return {owner for _, owner in self._entries}

    def owner_of(self, authorization: str | None) -> str | None:
        """The owner of the bearer token in an Authorization header, or None."""
        if not authorization:
            return None
        scheme, _, token = authorization.partition(" ")
        if scheme.lower() != "bearer" or not token.strip():
            return None
        given = _digest(token.strip())
        found = None
        for digest, owner in self._entries:  # every entry, so the time does not tell which matched
            if hmac.compare_digest(given, digest):
                found = owner
        return found


def load_tokens(setting: str | None) -> Tokens | None:
    """The tokens of MPM_API_TOKENS (None when unset or blank)."""
    if setting is None or not setting.strip():
        return None
    text = setting.strip()
    if text.startswith("@"):
        path = Path(text[1:]).expanduser()
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as exc:
            raise TokenError(f"MPM_API_TOKENS: cannot read the token file {path}: {exc.strerror}") from None
        entries = [line.strip() for line in text.splitlines()]
        entries = [line for line in entries if line and not line.startswith("#")]
    else:
        entries = [part.strip() for part in text.split(",") if part.strip()]
    pairs = []
    for number, entry in enumerate(entries, start=1):
        owner, colon, token = entry.partition(":")
        if not colon:
            raise TokenError(f"MPM_API_TOKENS entry {number}: expected owner:token")
        pairs.append((owner.strip(), token.strip()))
    return Tokens(pairs)


class TokenAuth:
    """ASGI middleware: a `/v1` request without a valid token is answered 401 before
    anything else reads it; a valid one puts its owner in the request state."""

    def __init__(self, app: ASGIApp, tokens: Tokens | None):
        self.app, self.tokens = app, tokens

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] == "http" and self.tokens is not None and _is_api(scope["path"]):
            header = dict(scope["headers"]).get(b"authorization")
            owner = self.tokens.owner_of(header.decode("latin-1") if header else None)
            if owner is None:
                message = ("a valid API token is required: Authorization: Bearer <token>" if header
                           else "this service needs an API token: Authorization: Bearer <token>")
                response = error_response(401, "unauthorized", message, headers=_UNAUTHORIZED_HEADERS)
                return await response(scope, receive, send)
            scope.setdefault("state", {})["owner"] = owner
        await self.app(scope, receive, send)


def _is_api(path: str) -> bool:
    return path == "/v1" or path.startswith("/v1/")


# Declares the scheme in the OpenAPI document; the middleware does the checking.
_bearer = HTTPBearer(auto_error=False, description="MPM_API_TOKENS: needed on /v1 when the service has tokens")


def caller(request: Request, _: HTTPAuthorizationCredentials | None = Security(_bearer)) -> str | None:
    """FastAPI dependency: the owner of the request's token; None when the service has no tokens.

    The middleware has already refused a request without a valid token; this checks
    again so that a route can never run unauthenticated on a token-protected service."""
    owner = request.scope.get("state", {}).get("owner")
    if owner is None and request.app.state.tokens is not None:
        raise ApiError(401, "unauthorized", "this service needs an API token: Authorization: Bearer <token>",
                       headers=_UNAUTHORIZED_HEADERS)
    return owner


def owns(record: dict, owner: str | None) -> bool:
    """Whether the caller may see the job (anyone may, on a service without tokens)."""
    return owner is None or record.get("owner") == owner


def access_notice(tokens: Tokens | None, host: str) -> str:
    """What `mpm serve` says at start about who can use the service."""
    if tokens is not None:
        return f"API tokens for {len(tokens.owners)} owner(s): every /v1 call needs one"
    if host in ("127.0.0.1", "localhost", "::1"):
        return (f"no MPM_API_TOKENS: listening on {host} only, open to anyone on this machine "
                "(set tokens before --host)")
    return (f"WARNING: no MPM_API_TOKENS and listening on {host}: anyone who can reach this port "
            "can submit, read and delete jobs")
