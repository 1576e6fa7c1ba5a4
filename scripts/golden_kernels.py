#!/usr/bin/env python3
"""Write docs/kernels/fused_2d.py and fused_3d.py: the fused P2G and G2P kernels as
solver/fused_template.py generates them for a scene without heat, contact or a
generated stress (uncontracted, MPM_FMA=0), so a reader can see a generated kernel
without running the solver, and a template change shows up in review as a change of
these files (tests/unit/test_fused_golden.py holds them equal to the template's text).

    .venv/bin/python scripts/golden_kernels.py
"""
from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from solver import fused_template  # noqa: E402

FOLDER = ROOT / "docs" / "kernels"


def golden_text(dim: int) -> str:
    return fused_template.source(dim, contract=False)


def golden_path(dim: int) -> Path:
    return FOLDER / f"fused_{dim}d.py"


def main() -> None:
    FOLDER.mkdir(exist_ok=True)
    for dim in (2, 3):
        golden_path(dim).write_text(golden_text(dim))
        print(golden_path(dim).relative_to(ROOT))


if __name__ == "__main__":
    main()
