"""How often a long run tells its log it is alive: runs a command with its output to a
pipe (not a terminal, as a batch job or `> run.log` has it), prints every line with the
seconds since the start, then the number of lines and the longest silence between two.

Run (the whole 2023-11-13 snapshot, as docs/conventions.md "Progress" reports it):

    python benches/log_gaps.py rhoprop catalog \\
        $RHOPROP_TEST_DATA/catalogs/celestrak_active_20231113.txt.gz --end 2023-11-16T00:00
    python benches/log_gaps.py rhoprop screen \\
        $RHOPROP_TEST_DATA/catalogs/celestrak_active_20231113.txt.gz --end 2023-11-16T12:00
"""

from __future__ import annotations

import subprocess
import sys
import time

from machine import describe


def main() -> None:
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    print(describe(), flush=True)
    t0 = time.monotonic()
    last, gaps = t0, []
    with subprocess.Popen(
        sys.argv[1:], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1
    ) as proc:
        assert proc.stdout is not None
        for line in proc.stdout:
            now = time.monotonic()
            gaps.append((now - last, line.rstrip()[:100]))
            last = now
            print(f"{now - t0:7.1f} {line.rstrip()[:140]}", flush=True)
    end = time.monotonic()
    gaps.append((end - last, "<end>"))
    longest, before = max(gaps)
    print(
        f"exit {proc.returncode}; {end - t0:.0f} s; {len(gaps) - 1} lines; longest silence "
        f"{longest:.1f} s, before: {before}"
    )


if __name__ == "__main__":
    main()
