#!/usr/bin/python3
"""No function longer than LIMIT lines (issue 16): universal-ctags gives each
function definition's first and last line. tests/ and bench/ are checked like
the rest; a TEST_CASE is a macro, not a function, and is not counted.

usage: check_function_size.py ROOT LIMIT DIR...
Prints every function over LIMIT lines as FILE:LINE: NAME is N lines, and
exits 1; exits 0 with one line when there is none. Exits 2 when ctags is not
universal-ctags (it alone gives end lines)."""

import json
import os
import subprocess
import sys

# A table is clearer as one function: none today. Keep entries as
# "path::name" with the reason beside them.
EXCEPTIONS = {}


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    root, limit, dirs = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
    ctags = next((c for c in ('ctags-universal', 'universal-ctags', 'ctags')
                  if any(os.access(os.path.join(p, c), os.X_OK) for p in os.environ.get('PATH', '').split(':'))), None)
    if ctags is None:
        print('check_function_size: universal-ctags not found (Debian package universal-ctags)')
        return 2
    run = subprocess.run([ctags, '-R', '--languages=C++', '--kinds-C++=f', '--fields=+ne', '--output-format=json',
                          '--exclude=node_modules', '-o', '-'] + dirs, cwd=root, capture_output=True, text=True)
    if run.returncode != 0 or not run.stdout:
        print(f'check_function_size: {ctags} failed: {run.stderr.strip() or "no output (not universal-ctags?)"}')
        return 2
    long_ones = []
    for line in run.stdout.splitlines():
        tag = json.loads(line)
        if tag.get('_type') != 'tag' or 'end' not in tag:
            continue
        n = tag['end'] - tag['line'] + 1
        name = (tag['scope'] + '::' if tag.get('scope') else '') + tag['name']
        if n > limit and f"{tag['path']}::{tag['name']}" not in EXCEPTIONS:
            long_ones.append((tag['path'], tag['line'], name, n))
    for path, line, name, n in sorted(long_ones):
        print(f'{path}:{line}: {name} is {n} lines (limit {limit})')
    if long_ones:
        print(f'{len(long_ones)} functions are over {limit} lines: split them along what they do')
        return 1
    print(f'function size: no function over {limit} lines in {" ".join(dirs)}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
