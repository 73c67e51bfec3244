#!/usr/bin/env python3
"""The OBJ files of a directory (thorax export --format obj) as one OBJ, each file's vertex numbers
moved past the vertices before it, for bench/trace.sh's Embree viewer. Usage: obj_merge.py DIR OUT"""
import glob
import sys

out, base = open(sys.argv[2], 'w'), 0
for f in sorted(glob.glob(sys.argv[1] + '/*.obj')):
    nv = 0
    for line in open(f):
        if line.startswith('v '):
            out.write(line)
            nv += 1
        elif line.startswith('f '):
            out.write('f ' + ' '.join(str(int(t.split('/')[0]) + base) for t in line.split()[1:]) + '\n')
    base += nv
