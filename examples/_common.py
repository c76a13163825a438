"""Shared by the example scripts: where figures go and how small to run.

Every example takes `--out DIR` (default: `$DDGJAX_EXAMPLES_OUT`, else `examples/out`) and
`--tiny` (small sizes, for tests), and exposes `main(out, tiny=False)`.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path


def output_dir(out=None) -> Path:
    """`out`, else `$DDGJAX_EXAMPLES_OUT`, else `examples/out`; created."""
    path = Path(out or os.environ.get("DDGJAX_EXAMPLES_OUT") or Path(__file__).parent / "out")
    path.mkdir(parents=True, exist_ok=True)
    return path


def run(main, description: str) -> None:
    """Parse `--out`/`--tiny` and call `main(out, tiny)`."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--out", help="directory for the figures (default: $DDGJAX_EXAMPLES_OUT or examples/out)")
    parser.add_argument("--tiny", action="store_true", help="small sizes (for tests)")
    args = parser.parse_args()
    main(output_dir(args.out), tiny=args.tiny)
