"""`python -m ddgjax …` is the `ddgjax` command line (`ddgjax.cli`)."""

import sys

from .cli import main

if __name__ == "__main__":  # not when a spawned worker of `ddgjax verify --jobs` imports it
    sys.exit(main())
