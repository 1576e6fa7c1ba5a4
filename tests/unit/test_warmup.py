"""The worker's warm-up (worker/warmup.py): only the variants not yet compiled, flagged while it runs."""
from worker import warmup


def test_a_warm_cache_starts_no_process_and_flags_nothing(monkeypatch):
    monkeypatch.setattr(warmup, "pending", lambda threads: [])
    monkeypatch.setattr(warmup, "_compile", lambda *a: (_ for _ in ()).throw(AssertionError("compiled")))
    flags = []
    warmup.warm_up(warming=flags.append)
    assert flags == []


def test_each_pending_variant_compiles_once_while_flagged(monkeypatch):
    flags, compiled = [], []
    monkeypatch.setattr(warmup, "pending", lambda threads: [(2, "linear_elastic", 1), (3, "neo_hookean", 2)])
    monkeypatch.setattr(warmup, "_compile",
                        lambda dim, model, threads, folder, timeout: compiled.append((dim, model, threads, flags[:])))
    warmup.warm_up(warming=flags.append, workers=2)
    assert sorted(compiled) == [(2, "linear_elastic", 1, [True]), (3, "neo_hookean", 2, [True])]
    assert flags == [True, False]


def test_pending_leaves_out_the_variants_a_run_marked_compiled(monkeypatch):
    from solver import cost

    monkeypatch.setattr(cost, "is_compiled", lambda scene, threads: scene.dimension == 1 or threads == 1)
    assert warmup.pending(threads=(1, 2)) == [(dim, model, 2) for dim, model in warmup.WARMUP if dim != 1]


def test_the_warm_up_compiles_the_parallel_forms_only_for_jobs_that_may_take_several_cores():
    assert warmup.thread_counts(1) == (1,)
    assert warmup.thread_counts(4) == (1, 4)
