"""The worker's warm-up (worker/warmup.py): only the variants not yet compiled, flagged while it runs."""
from worker import warmup


def test_a_warm_cache_starts_no_process_and_flags_nothing(monkeypatch):
    monkeypatch.setattr(warmup, "pending", lambda: [])
    monkeypatch.setattr(warmup, "_compile", lambda *a: (_ for _ in ()).throw(AssertionError("compiled")))
    flags = []
    warmup.warm_up(warming=flags.append)
    assert flags == []


def test_each_pending_variant_compiles_once_while_flagged(monkeypatch):
    flags, compiled = [], []
    monkeypatch.setattr(warmup, "pending", lambda: [(2, "linear_elastic"), (3, "neo_hookean")])
    monkeypatch.setattr(warmup, "_compile", lambda dim, model, folder, timeout: compiled.append((dim, model, flags[:])))
    warmup.warm_up(warming=flags.append, workers=2)
    assert sorted(compiled) == [(2, "linear_elastic", [True]), (3, "neo_hookean", [True])]
    assert flags == [True, False]


def test_pending_leaves_out_the_variants_a_run_marked_compiled(monkeypatch):
    from solver import cost

    monkeypatch.setattr(cost, "is_compiled", lambda scene: scene.dimension == 1)
    assert warmup.pending() == [variant for variant in warmup.WARMUP if variant[0] != 1]
