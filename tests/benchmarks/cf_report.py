"""CF compliance of the result files: the IOOS compliance-checker (``--test cf:1.11``) on every
file each built-in scene writes.

    python tests/benchmarks/cf_report.py [SCENE ...] [--outdir DIR] [--smoke]

Runs each scene (default: every built-in scene) into a fresh folder and prints, per result
file, the errors the checker reports (its "Errors" section: high-priority findings), then the
total. Exit status 1 if any file has an error. Needs the test extra (compliance-checker).
--smoke: the friction scene only (seconds, for CI).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

CF = "cf:1.11"


def cf_errors(path: Path) -> list[str]:
    """The errors compliance-checker reports for ``path`` against CF-1.11 (empty: compliant)."""
    import warnings

    with warnings.catch_warnings():  # the checker's own deprecation notes on checkers we do not run
        warnings.simplefilter("ignore", DeprecationWarning)
        from compliance_checker.runner import CheckSuite, ComplianceChecker

        CheckSuite.load_all_available_checkers()
    with tempfile.TemporaryDirectory() as tmp:
        report = Path(tmp) / "report.json"
        ComplianceChecker.run_checker(str(path), [CF], 0, "normal", output_filename=str(report),
                                      output_format="json_new")
        result = json.loads(report.read_text())[str(path)][CF]
    return [f"{item['name']}: {msg}" for item in result["high_priorities"] for msg in item["msgs"]]


def result_files(outdir: Path) -> list[Path]:
    """The current result files of an output folder (not the kept ones of .results/)."""
    return sorted(p for p in Path(outdir).rglob("*.nc") if ".results" not in p.parts)


def main() -> int:
    from roughcontact import engine, scene as scenes

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenes", nargs="*", help="built-in scene names or files (default: every built-in scene)")
    ap.add_argument("--outdir", type=Path, help="where to run them (default: a temporary folder)")
    ap.add_argument("--smoke", action="store_true", help="the friction scene only (seconds)")
    args = ap.parse_args()
    names = args.scenes or (sorted(scenes.builtin_scenes()) if not args.smoke else ["friction"])
    total = 0
    with tempfile.TemporaryDirectory() as tmp:
        base = args.outdir or Path(tmp)
        for name in names:
            sc = scenes.load(name)
            out = base / sc.name
            t0 = time.perf_counter()
            engine.run(sc, out, report=engine.Reporter(None))
            took = time.perf_counter() - t0
            files = result_files(out)
            size = sum(f.stat().st_size for f in files)
            print(f"scene {name}: {len(files)} files, {size / 2**20:.1f} MiB, run {took:.1f} s")
            for f in files:
                errors = cf_errors(f)
                total += len(errors)
                print(f"  {f.relative_to(out)}: {len(errors)} error(s)")
                for e in errors:
                    print(f"    {e}")
    print(f"total: {total} error(s) from compliance-checker --test {CF}")
    return 1 if total else 0


if __name__ == "__main__":
    sys.exit(main())
