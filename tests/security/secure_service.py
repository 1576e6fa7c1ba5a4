"""A service with API tokens, as an operator starts it: `mpm serve` (API, a worker,
an embedded Redis) with MPM_API_TOKENS pointing to a token file. One instance is
shared by the security tests and the dashboard's token test, stopped at the session's end."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "clients"))

from live_service import LiveService, SessionService  # noqa: E402

# owner -> token (each at least 16 characters, as service/auth.py requires)
TOKENS = {"alice": "alice-token-0123456789abcdef", "bob": "bob-token-0123456789abcdef",
          "fuzz": "fuzz-token-0123456789abcdef"}


def bearer(owner: str) -> dict[str, str]:
    return {"Authorization": f"Bearer {TOKENS[owner]}"}


class SecureService(LiveService):
    serve_options = ("--access-log",)  # the tests check that no token reaches the log

    def __init__(self, root: Path) -> None:
        (root / "data").mkdir()
        super().__init__(root / "data", root / "serve.log")
        self.token_file = root / "tokens.txt"
        self.token_file.write_text("# owner:token, one a line\n" +
                                   "".join(f"{owner}:{token}\n" for owner, token in TOKENS.items()))

    def environment(self) -> dict[str, str]:
        env = super().environment()
        env.update({"MPM_API_TOKENS": f"@{self.token_file}", "MPM_MAX_BODY_BYTES": "300000"})
        return env


_shared = SessionService()


def shared_secure_service(config: pytest.Config, tmp_path_factory: pytest.TempPathFactory) -> SecureService:
    return _shared.get(config, lambda: SecureService(tmp_path_factory.mktemp("mpm-secure")).start())
