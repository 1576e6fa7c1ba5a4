"""CORS is off by default: no page of another origin may call the API from a browser.
MPM_CORS_ORIGINS lets the origins listed do so (preflights need no token)."""
from __future__ import annotations

from quota_api import QuotaApi

ORIGIN = "https://dashboard.example"


def test_cors_is_off_by_default(secure, alice):
    answer = alice.get("/v1/jobs", headers={"Origin": ORIGIN})
    assert answer.status_code == 200 and "access-control-allow-origin" not in answer.headers
    preflight = alice.options("/v1/jobs", headers={"Origin": ORIGIN, "Access-Control-Request-Method": "POST"})
    assert "access-control-allow-origin" not in preflight.headers


def test_listed_origins_may_call_the_api(tmp_path):
    api = QuotaApi(tmp_path, {"MPM_CORS_ORIGINS": f"{ORIGIN}, https://other.example"})
    try:
        with api.client("alice") as alice:
            preflight = alice.options("/v1/jobs", headers={
                "Origin": ORIGIN, "Access-Control-Request-Method": "POST",
                "Access-Control-Request-Headers": "authorization, content-type",
                "Authorization": ""})  # a browser sends a preflight without the token
            assert preflight.status_code == 200
            assert preflight.headers["access-control-allow-origin"] == ORIGIN
            assert "authorization" in preflight.headers["access-control-allow-headers"].lower()
            answer = alice.get("/v1/jobs", headers={"Origin": ORIGIN})
            assert answer.headers["access-control-allow-origin"] == ORIGIN
            stranger = alice.get("/v1/jobs", headers={"Origin": "https://evil.example"})
            assert "access-control-allow-origin" not in stranger.headers
    finally:
        api.stop()
