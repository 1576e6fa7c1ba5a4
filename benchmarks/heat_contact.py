"""Heat with contact: the errors and times of tests/verification/test_heat_contact.py's
cases (docs/benchmarks.md, "Heat", "Contact: conduction and frictional heat").

    python benchmarks/heat_contact.py

The cost of a contact step with conduction: `python benchmarks/contact_cost.py --heat`.
"""
from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "verification"))

import heat_contact_cases as hcc  # noqa: E402
from heat import timed  # noqa: E402   (benchmarks/heat.py)


def main() -> None:
    print("| case | measure | value | wall (s) |")
    print("|---|---|---|---|")
    (difference, error), wall = timed(hcc.split_bar_against_one, 24)
    print(f"| E12 bar as two bodies in contact, 24 cells | max abs(T_p - single field); error against the exact "
          f"series | {difference:.1e}; {error:.2e} | {wall:.2f} |")
    found, wall = timed(hcc.insulated_halves)
    change = abs(found["end"] - found["start"]) / found["start"]
    print(f"| halves at 400 / 300 K touching, insulated, 400 steps | abs(change of sum m c T) / sum m c T; "
          f"heat crossed (J) | {change:.1e}; {found['crossed']:.4g} | {wall:.2f} |")
    for support in ("wall", "rigid"):
        for transfer in ("pic", "flip"):
            found, wall = timed(hcc.sliding_heat, support, transfer=transfer)
            exact = abs(found["total_heat"] / found["total_friction_heat"] - 1)
            print(f"| block on the incline, {support}, {transfer.upper()}, 0.3 s | heat / -friction_work - 1; "
                  f"heat / (mu N d) - 1 over 0.1-0.3 s; mechanical energy_error / heat | {exact:.1e}; "
                  f"{found['heat'] / found['coulomb'] - 1:+.1e}; "
                  f"{found['mechanical_error'] / found['total_heat']:+.1e} | {wall:.1f} |")


if __name__ == "__main__":
    main()
