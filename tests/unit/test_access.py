"""The pieces of the HTTP edge that need no service: reading MPM_API_TOKENS,
matching a bearer token to its owner, measuring a body's JSON nesting."""
from __future__ import annotations

import json

import pytest

from service.auth import TokenError, access_notice, load_tokens
from service.json_depth import nesting_depth

ALICE, BOB = "alice-token-0123456789", "bob-token-0123456789"


def test_tokens_from_a_list_and_from_a_file(tmp_path):
    listed = load_tokens(f" alice:{ALICE} , bob:{BOB},alice:{ALICE}-rotated ")
    token_file = tmp_path / "tokens"
    token_file.write_text(f"# who may use it\nalice:{ALICE}\n\nbob:{BOB}\nalice:{ALICE}-rotated\n")
    from_file = load_tokens(f"@{token_file}")
    for tokens in (listed, from_file):
        assert tokens.owners == {"alice", "bob"}
        assert tokens.owner_of(f"Bearer {ALICE}") == "alice"
        assert tokens.owner_of(f"bearer {ALICE}-rotated") == "alice"
        assert tokens.owner_of(f"Bearer {BOB}") == "bob"
        for wrong in (None, "", ALICE, f"Basic {ALICE}", f"Bearer {ALICE[:-1]}", "Bearer", f"Bearer {ALICE}x"):
            assert tokens.owner_of(wrong) is None, wrong
    assert load_tokens(None) is None and load_tokens("  ") is None


@pytest.mark.parametrize("setting,words", [
    ("alice", "expected owner:token"),
    (f"../x:{ALICE}", "the owner must be"),
    ("alice:short", "at least 16 characters"),
    (f"alice:{ALICE},bob:{ALICE}", "the same token is given twice"),
    (",", "names no token"),
    ("@/no/such/file", "cannot read the token file"),
])
def test_bad_token_settings_are_refused_without_showing_the_token(setting, words):
    with pytest.raises(TokenError) as error:
        load_tokens(setting)
    assert words in str(error.value)
    secrets = [entry.split(":", 1)[1] for entry in setting.split(",") if ":" in entry and entry[0] != "@"]
    assert not any(secret in str(error.value) for secret in secrets)


def test_the_start_notice_says_who_can_reach_the_service():
    assert "127.0.0.1 only" in access_notice(None, "127.0.0.1")
    assert access_notice(None, "0.0.0.0").startswith("WARNING")
    assert "2 owner(s)" in access_notice(load_tokens(f"alice:{ALICE},bob:{BOB}"), "0.0.0.0")


def test_nesting_depth_ignores_brackets_in_strings():
    document = {"a": [1, {"b": "[[[{{{"}], "c": "\\\"]]]"}
    assert nesting_depth(json.dumps(document).encode()) == 3
    assert nesting_depth(b"[" * 100_000 + b"]" * 100_000) == 100_000
    assert nesting_depth(b"1") == 0
