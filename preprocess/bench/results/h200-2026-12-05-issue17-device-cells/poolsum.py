#!/usr/bin/env python3
"""Prints one line per section of a pool (type, count, bytes, XXH3 checksum from the section table),
provenance left out: two pools with the same lines hold the same sections byte for byte."""
import struct, sys
with open(sys.argv[1], "rb") as f:
    head = f.read(64)
    count, = struct.unpack_from("<I", head, 24)
    table, = struct.unpack_from("<Q", head, 32)
    f.seek(table)
    for i in range(count):
        e = f.read(64)
        typ, ver, off, size, n, esz, flags, chk = struct.unpack_from("<IIQQQIIQ", e, 0)
        if typ != 1:
            print(typ, n, size, "%016x" % chk)
