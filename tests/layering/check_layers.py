#!/usr/bin/python3
"""The layering rule: a folder includes its own layer's headers and those of
the layers below it, never one above it (the order is the top
CMakeLists.txt's RISE_LAYERS, lowest first; "a|b" are peers of one layer).
tests/ and bench/ sit above every layer.

usage: check_layers.py ROOT cli,firmware_protocol,...,app
Prints every #include "..." that breaks the rule as FILE:LINE and exits 1;
exits 0 with one line when there is none."""

import os
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')
SOURCES = ('.c', '.cc', '.cpp', '.h', '.hpp')


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    root, layers = sys.argv[1], [layer.split('|') for layer in sys.argv[2].split(',') if layer]
    rank = {d: i for i, peers in enumerate(layers) for d in peers}
    rank['tests'] = rank['bench'] = len(layers)
    # The longest folder first: hil/io is its own layer inside hil.
    folders = sorted(rank, key=len, reverse=True)

    def layer_of(path):
        return next((d for d in folders if path == d or path.startswith(d + '/')), None)

    broken = []
    for peers in layers:
        for top in peers:
            for dirpath, dirnames, filenames in os.walk(os.path.join(root, top)):
                dirnames[:] = [d for d in dirnames if d != 'node_modules']
                for name in sorted(filenames):
                    if not name.endswith(SOURCES):
                        continue
                    path = os.path.relpath(os.path.join(dirpath, name), root)
                    own = layer_of(path)
                    if own != top and own in rank and rank[own] != rank[top]:
                        continue  # a nested layer's file: checked under its own folder
                    with open(os.path.join(root, path), encoding='utf-8', errors='replace') as f:
                        for number, line in enumerate(f, 1):
                            m = INCLUDE.match(line)
                            if not m:
                                continue
                            target = layer_of(m.group(1))
                            if target is not None and rank[target] > rank[own]:
                                broken.append(f'{path}:{number}: includes "{m.group(1)}" of {target}/, '
                                              f'a layer above {own}/')
    for b in broken:
        print(b)
    if broken:
        print(f'{len(broken)} includes break the layering (order: {" -> ".join("|".join(p) for p in layers)})')
        return 1
    print(f'layering: no folder includes one above it ({" -> ".join("|".join(p) for p in layers)})')
    return 0


if __name__ == '__main__':
    sys.exit(main())
