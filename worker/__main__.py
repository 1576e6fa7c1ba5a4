"""`python -m worker`: the same as `mpm worker` (how `mpm serve` starts its worker)."""
import argparse
import sys

from worker.cli import add_arguments, worker_command

parser = argparse.ArgumentParser(prog="python -m worker")
add_arguments(parser)
sys.exit(worker_command(parser.parse_args()))
