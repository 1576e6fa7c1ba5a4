"""`python -m service`: the same as `mpm serve`."""
import argparse
import sys

from service.cli import add_arguments, serve_command

parser = argparse.ArgumentParser(prog="python -m service")
add_arguments(parser)
sys.exit(serve_command(parser.parse_args()))
