"""Run under mpiexec: advance a scene N steps; rank 0 prints the particles each process
holds and the slab cuts at the start and at the end, as JSON. A third argument D makes
rank 0 slow: it sleeps D seconds per particle it holds at the end of every step."""
import json
import sys
import time
from pathlib import Path

from solver.scene_checks import load_scene
from solver.stepper import ExplicitMPM

scene = load_scene(Path(sys.argv[1]))
sim = ExplicitMPM(scene)
start = sim.domain.cuts.tolist()


class SlowRankZero:
    def __init__(self, delay: float):
        self.delay = delay

    def end_step(self, sim, dt):
        if sim.domain.rank == 0:
            time.sleep(self.delay * sim.particles.count)


if len(sys.argv) > 3:
    sim.add_hook(SlowRankZero(float(sys.argv[3])))
for _ in range(int(sys.argv[2])):
    sim.advance(scene.time.dt)
counts = sim.domain.comm.gather(sim.particles.count, root=0)
if sim.domain.is_root:
    print(json.dumps({"counts": counts, "cuts_start": start, "cuts_end": sim.domain.cuts.tolist()}))
