"""The API's own checks of issue 49, without a running service: the safety net under scene
validation, and the JSON body rules (the live answers are in tests/security)."""
import pytest

from service import scenes
from service.errors import ApiError
from service.json_depth import _long_integer
from service.settings import ApiSettings

from test_scene_validation import two_disks


def test_an_overflow_no_rule_foresaw_is_a_422_not_a_500(monkeypatch):
    def overflowing(scene):
        raise OverflowError("(34, 'Numerical result out of range')")
    monkeypatch.setattr(scenes, "summarize", overflowing)
    with pytest.raises(ApiError) as caught:
        scenes.check_scene(two_disks(), ApiSettings())
    assert caught.value.status == 422
    assert "out of the range of double precision" in caught.value.details[0]["message"]


@pytest.mark.parametrize("body,found", [
    (b'{"a":\n  ' + b"1" * 5000 + b"}", (2, 3)),
    (b'{"a": -' + b"1" * 5000 + b"}", (1, 8)),
    (b'{"a": 1.' + b"1" * 5000 + b"}", None),     # a fraction: float() reads it
    (b'{"a": 1e-' + b"1" * 5000 + b"}", None),    # an exponent likewise
    (b'{"a": "' + b"1" * 5000 + b'"}', None),     # a string
    (b'{"a": ' + b"1" * 4300 + b"}", None),       # at the limit
])
def test_an_integer_too_long_to_read_is_found_with_its_line_and_column(body, found):
    problem = _long_integer(body)
    assert (problem and (problem["line"], problem["column"])) == found or (problem is None and found is None)
