"""The `hppm` command line, installed with the package (`python -m hppm` runs it too)."""

import sys

from ._hppm import cli


def main():
    sys.exit(cli(sys.argv))


if __name__ == "__main__":
    main()
