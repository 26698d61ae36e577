"""What the benchmark scripts share (not a benchmark: tests/test_benchmarks.py skips files
starting with an underscore).

Every script in this folder takes ``--smoke``: the same code path at tiny sizes, in seconds, so
that CI (tests/test_benchmarks.py) runs each one and none can rot. Its numbers mean nothing;
benchmarks print ratios and never assert wall-clock times.
"""

from __future__ import annotations

import sys
from pathlib import Path

#: tests/ (for _synthetic and reference_solutions) and the repository root
TESTS = Path(__file__).resolve().parent.parent
ROOT = TESTS.parent
if str(TESTS) not in sys.path:
    sys.path.insert(0, str(TESTS))

#: True when the script was started with --smoke (argparse scripts also declare the flag)
SMOKE = "--smoke" in sys.argv


def positional(argv: list[str]) -> list[str]:
    """The command-line arguments without the --smoke flag."""
    return [a for a in argv if a != "--smoke"]


def stage_result(name: str, sc, upstream=None, **params):
    """Stage ``name``'s compute on scene ``sc``, its declared keys read from the scene (as the
    engine hands them; ``params`` overrides some), without the engine's planning and storage."""
    from roughcontact.stage import StageInput, stages

    st = stages()[name]
    values = {k: st.section_view(k, sc.get(k)) for k in st.keys}
    values.update(params)
    return st.compute(StageInput(params=values, upstream=upstream or {}, stage=name))
