import struct, sys
def table(path):
    with open(path, 'rb') as f:
        h = f.read(64)
        count, = struct.unpack_from('<I', h, 24); off, = struct.unpack_from('<Q', h, 32)
        f.seek(off); t = f.read(64 * count)
    return {struct.unpack_from('<I', t, 64*i)[0]: struct.unpack_from('<QQ', t, 64*i+16)[0:1] + struct.unpack_from('<Q', t, 64*i+40) for i in range(count)}
a, b = table(sys.argv[1]), table(sys.argv[2])
types = [int(x) for x in sys.argv[3].split(',')]
ok = all(a.get(t) == b.get(t) and t in a for t in types)
for t in types: print(t, a.get(t), b.get(t))
print('EQUAL' if ok else 'DIFFERENT'); sys.exit(0 if ok else 1)
