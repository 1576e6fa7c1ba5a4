"""docs/kernels/fused_{2,3}d.py are the fused kernels as the template writes them today: a
reader's copy of generated code, and a template change shows in review as a change of them."""
from pathlib import Path

import pytest

from solver import fused_template

DOCS = Path(__file__).resolve().parents[2] / "docs" / "kernels"


@pytest.mark.parametrize("dim", [2, 3])
def test_the_checked_in_kernels_are_the_templates_output(dim):
    golden = (DOCS / f"fused_{dim}d.py").read_text()
    assert fused_template.source(dim, contract=False) == golden, (
        f"docs/kernels/fused_{dim}d.py is not what solver/fused_template.py writes now: "
        "run `.venv/bin/python scripts/golden_kernels.py` and review the difference")
