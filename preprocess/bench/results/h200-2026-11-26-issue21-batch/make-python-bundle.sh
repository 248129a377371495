#!/bin/bash
# make-python-bundle.sh BUNDLE_DIR
#
# Builds a relocatable copy of Debian 12's Python 3.11 with Dask distributed (and psutil, xxhash,
# cloudpickle) in BUNDLE_DIR, so that scripts/prt-batch runs on a host without those packages and
# without a package registry (issue 21, GPU host runs). Then packs BUNDLE_DIR.tar.gz beside it and
# checks the result in an empty environment (env -i).
#
# Run on Debian 12 with python3.11 python3-distributed python3-dask python3-psutil python3-xxhash
# python3-cloudpickle installed (scripts/install-deps.sh). Needs no root and no network.
#
# Layout (PYTHONHOME = BUNDLE_DIR, as /usr is for Debian's python):
#   bin/python3.11                   Debian's interpreter, unchanged
#   bin/python3, bin/python          launcher: sets PYTHONHOME, PYTHONPATH, LD_LIBRARY_PATH,
#                                    PYTHONNOUSERSITE=1 and execs bin/python3.11
#   lib/*.so.*                       the shared libraries the interpreter and its extension modules
#                                    need that are not part of glibc (nor libstdc++/libgcc_s)
#   lib/python3.11/                  the standard library, pruned; lib-dynload/ its C modules
#   lib/python3/dist-packages/       the packages that `import distributed` and a LocalCluster run
#                                    actually import (found by running one, see probe below)
#   lib/python3.11/sitecustomize.py  gives the caller's environment back to child processes (the
#                                    tools that workers run must not inherit PYTHONHOME or the
#                                    bundle's LD_LIBRARY_PATH); points sys.executable at the launcher
#                                    so that multiprocessing's spawned Dask workers get it again
#
# On the remote host:  tar -xzf pybundle.tar.gz -C /opt && /opt/pybundle/bin/python3 scripts/prt-batch ...
set -euo pipefail

PY=/usr/bin/python3.11
SYS_STDLIB=/usr/lib/python3.11
SYS_DIST=/usr/lib/python3/dist-packages
HERE=$(cd "$(dirname "$0")" && pwd)
REPO=$(cd "$HERE/../../../.." && pwd)   # preprocess/bench/results/<run>/ -> repository root

[ $# -eq 1 ] || { echo "usage: $0 BUNDLE_DIR   (e.g. /tmp/pybundle)" >&2; exit 2; }
case "$1" in /*) B=$1 ;; *) B=$PWD/$1 ;; esac
B=${B%/}
[ -x "$PY" ] || { echo "$0: $PY is missing (Debian 12 python3.11)" >&2; exit 1; }
"$PY" -c 'import distributed, dask, psutil, xxhash, cloudpickle' ||
    { echo "$0: install python3-distributed python3-dask python3-psutil python3-xxhash python3-cloudpickle" >&2; exit 1; }

rm -rf "$B" "$B.tar.gz"
mkdir -p "$B/bin" "$B/lib/python3/dist-packages"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

# ---- 1. the import closure: every module file loaded in the client, the scheduler and the workers
# of a LocalCluster that runs tasks the way prt-batch does (prt_dask.start_client when available).
cat > "$WORK/probe.py" <<'EOF'
import json, logging, os, shutil, sys
lib = sys.argv[2]
if os.path.isfile(os.path.join(lib, "prt_dask.py")):
    sys.path.insert(0, lib)
    import prt_dask, prt_provenance
else:
    prt_dask = prt_provenance = None
import argparse, atexit, glob, re, shlex, signal, subprocess, tempfile, time, uuid  # prt-batch's own
import cloudpickle, dask, psutil, xxhash
from distributed import Client, LocalCluster, as_completed

def files():
    import sys
    return sorted({m.__file__ for m in list(sys.modules.values()) if getattr(m, "__file__", None)})

def work(x):
    import subprocess
    subprocess.run(["true"], check=True)
    if x == 0:
        raise ValueError("a failing task")
    return xxhash.xxh3_64_hexdigest(b"%d" % x)

if __name__ == "__main__":
    logging.getLogger("distributed").setLevel(logging.ERROR)
    state = {}
    if prt_dask:
        client, cluster = prt_dask.start_client("probe", 2, None, state, by_value=(prt_provenance,))
    else:
        cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0")
        client = Client(cluster)
    futures = [client.submit(work, i, pure=False, retries=1) for i in range(6)]
    for f in as_completed(futures):
        f.exception() if f.status != "finished" else f.result()
    found = set(files())
    for fl in client.run(files).values():
        found.update(fl)
    found.update(client.run_on_scheduler(files))
    client.close()
    cluster.close()
    if state.get("scratch"):
        shutil.rmtree(state["scratch"], ignore_errors=True)
    json.dump(sorted(found), open(sys.argv[1], "w"), indent=0)
EOF
echo "probing the import closure with $PY ..."
(cd "$WORK" && env -u PYTHONPATH -u PYTHONHOME PYTHONNOUSERSITE=1 PYTHONDONTWRITEBYTECODE=1 timeout 300 "$PY" probe.py "$WORK/mods.json" "$REPO/scripts/lib" \
    >"$WORK/probe.log" 2>&1) || { cat "$WORK/probe.log" >&2; echo "$0: the probe failed" >&2; exit 1; }

# Top-level names under dist-packages that were imported. Left out: optional imports that a
# missing module does not break (numpy: distributed's try/except for a buffer allocator;
# colorama: tornado/click colours; _distutils_hack: a .pth hook of setuptools).
OPTIONAL_OUT="numpy colorama _distutils_hack"
"$PY" - "$WORK/mods.json" "$SYS_DIST" "$OPTIONAL_OUT" > "$WORK/tops" <<'EOF'
import json, sys
dist = sys.argv[2].rstrip("/") + "/"
skip = set(sys.argv[3].split())
tops = set()
for f in json.load(open(sys.argv[1])):
    if f.startswith(dist):
        t = f[len(dist):].split("/")[0]
        if t not in skip and t != "__pycache__":
            tops.add(t)
print("\n".join(sorted(tops)))
EOF
echo "dist-packages imported: $(tr '\n' ' ' < "$WORK/tops")"

# ---- 2. interpreter and standard library
cp -p "$PY" "$B/bin/python3.11"
# The standard library, without: tests, build files (config-*: libpython.a, 25 MB), bytecode (rebuilt
# below), Debian's system dist-packages (numpy), tools never used by a batch run, and the modules
# whose C parts need libraries not copied (curses, dbm, sqlite3, readline, nis, crypt).
tar -C "$SYS_STDLIB" -ch \
    --exclude=__pycache__ --exclude='./test' --exclude='./idlelib' --exclude='./tkinter' \
    --exclude='./turtledemo' --exclude='./lib2to3' --exclude='./ensurepip' --exclude='./venv' \
    --exclude='./pydoc_data' --exclude='./config-3.11-*' --exclude='./dist-packages' \
    --exclude='./sqlite3' --exclude='./dbm' --exclude='./curses' --exclude='./EXTERNALLY-MANAGED' \
    --exclude='./sitecustomize.py' --exclude='./turtle.py' --exclude='./__phello__' --exclude='./distutils' \
    --exclude='./lib-dynload/_test*' --exclude='./lib-dynload/_xx*' --exclude='./lib-dynload/xx*' \
    --exclude='./lib-dynload/_ctypes_test*' --exclude='./lib-dynload/_curses*' \
    --exclude='./lib-dynload/_dbm*' --exclude='./lib-dynload/_gdbm*' --exclude='./lib-dynload/_sqlite3*' \
    --exclude='./lib-dynload/readline*' --exclude='./lib-dynload/nis*' --exclude='./lib-dynload/_crypt*' \
    --exclude='./lib-dynload/ossaudiodev*' --exclude='./lib-dynload/audioop*' \
    . | tar -C "$B/lib" --transform='s,^\.,python3.11,' -x
# (-h: Debian's _sysconfigdata__linux_x86_64-linux-gnu.py is a symbolic link)

cat > "$B/lib/python3.11/sitecustomize.py" <<'EOF'
# Python bundle (make-python-bundle.sh): bin/python3 set PYTHONHOME, PYTHONPATH, LD_LIBRARY_PATH and
# PYTHONNOUSERSITE for this interpreter only. Give child processes (the tools Dask workers run, or
# another Python) the caller's environment back; this process keeps its libraries (the dynamic
# loader read LD_LIBRARY_PATH at start). Python children started through sys.executable (Dask's
# spawned workers) go through the launcher again.
import os
import sys

_home = os.environ.get("PYBUNDLE_HOME")
if _home:
    for _name in ("LD_LIBRARY_PATH", "PYTHONHOME", "PYTHONPATH", "PYTHONNOUSERSITE"):
        _saved = os.environ.pop("PYBUNDLE_SAVED_" + _name, None)
        if _saved is None:
            os.environ.pop(_name, None)
        else:
            os.environ[_name] = _saved[1:]  # "=" + the value (an empty value stays distinct from unset)
    del os.environ["PYBUNDLE_HOME"]
    _launcher = os.path.join(_home, "bin", "python3")
    if os.access(_launcher, os.X_OK):
        sys.executable = _launcher
    del _name, _saved, _launcher
del _home
EOF

# ---- 3. the packages of the closure, with their metadata (importlib.metadata finds versions)
while read -r top; do
    cp -a "$SYS_DIST/$top" "$B/lib/python3/dist-packages/"
done < "$WORK/tops"
"$PY" - "$SYS_DIST" "$B/lib/python3/dist-packages" <<'EOF'
import glob, os, shutil, sys
src, dst = sys.argv[1], sys.argv[2]
have = {n[:-3] if n.endswith(".py") else n for n in os.listdir(dst)}
for meta in glob.glob(os.path.join(src, "*.egg-info")) + glob.glob(os.path.join(src, "*.dist-info")):
    tops = set()
    for name in ("top_level.txt",):
        p = os.path.join(meta, name)
        if os.path.isfile(p):
            tops.update(l.strip() for l in open(p) if l.strip())
    if not tops:
        p = os.path.join(meta, "RECORD")
        if os.path.isfile(p):
            tops.update(l.split("/")[0].split(",")[0].removesuffix(".py") for l in open(p))
    if not tops:  # egg-info with no top_level.txt: guess from the distribution name
        tops.add(os.path.basename(meta).split("-")[0].lower())
    if tops & have:
        (shutil.copytree if os.path.isdir(meta) else shutil.copy2)(meta, os.path.join(dst, os.path.basename(meta)))
EOF
# Their test suites (16 MB), and dask.array and dask.dataframe, which need numpy and pandas (not
# copied: importing them fails with ImportError either way).
find "$B/lib/python3/dist-packages" -type d \( -name __pycache__ -o -name tests -o -name test \) -prune -exec rm -rf {} +
rm -rf "$B/lib/python3/dist-packages/dask/array" "$B/lib/python3/dist-packages/dask/dataframe"

# ---- 4. shared libraries: what ldd resolves for the interpreter and every extension module, less
# glibc's own (libc, libm, libpthread, libdl, librt, libutil, libresolv, ld-linux) and the C++
# runtime (libstdc++, libgcc_s: every host with g++ has them, and a newer one than Debian 12's).
SYSLIBS='^(linux-vdso|libc\.so|libm\.so|libpthread\.so|libdl\.so|librt\.so|libutil\.so|libresolv\.so|ld-linux|libstdc\+\+\.so|libgcc_s\.so)'
{ echo "$B/bin/python3.11"; find "$B/lib" -name '*.so'; } | while read -r f; do
    ldd "$f" | awk '$2 == "=>" && $3 ~ /^\// {print $1, $3}'
done | sort -u | while read -r name path; do
    if ! [[ $name =~ $SYSLIBS ]]; then
        cp -L "$path" "$B/lib/$name"
    fi
done
# libraries those libraries need (libssl -> libcrypto): one more pass
for f in "$B"/lib/*.so.*; do
    ldd "$f" | awk '$2 == "=>" && $3 ~ /^\// {print $1, $3}'
done | sort -u | while read -r name path; do
    if ! [[ $name =~ $SYSLIBS ]] && [ ! -e "$B/lib/$name" ]; then
        cp -L "$path" "$B/lib/$name"
    fi
done
chmod u+w "$B"/lib/*.so.*
strip --strip-unneeded "$B"/lib/*.so.* 2>/dev/null || true
# Debian 12's libexpat needs glibc 2.36 (arc4random_buf), the rest of the bundle 2.35. The
# interpreter uses only expat calls that every libexpat.so.1 has, so the host's copy is used where
# there is one (any host with a Python has it); lib/fallback/ is used only where there is none.
mkdir -p "$B/lib/fallback"
mv "$B/lib/libexpat.so.1" "$B/lib/fallback/"

# ---- 5. the launcher
cat > "$B/bin/python3" <<'EOF'
#!/bin/sh
# Python 3.11 bundle (make-python-bundle.sh): runs bin/python3.11 on this folder's libraries only.
self=$(readlink -f "$0") || self=$0
home=$(cd "$(dirname "$self")/.." && pwd -P)
for v in LD_LIBRARY_PATH PYTHONHOME PYTHONPATH PYTHONNOUSERSITE; do   # given back by sitecustomize
    if eval "[ -n \"\${$v+set}\" ]"; then eval "export PYBUNDLE_SAVED_$v=\"=\$$v\""; else unset "PYBUNDLE_SAVED_$v"; fi
done
export PYBUNDLE_HOME="$home"
export PYTHONHOME="$home"
export PYTHONPATH="$home/lib/python3/dist-packages"
export PYTHONNOUSERSITE=1
libs="$home/lib"
have_expat=
for d in /lib/x86_64-linux-gnu /usr/lib/x86_64-linux-gnu /lib64 /usr/lib64 /lib /usr/lib; do
    [ -e "$d/libexpat.so.1" ] && { have_expat=1; break; }
done
[ -n "$have_expat" ] || libs="$libs:$home/lib/fallback"   # lib/fallback: see make-python-bundle.sh
export LD_LIBRARY_PATH="$libs${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
exec "$home/bin/python3.11" "$@"
EOF
chmod 755 "$B/bin/python3"
ln -s python3 "$B/bin/python"

# ---- 6. bytecode, compiled by the bundle itself (saves every worker process compiling distributed)
env -i PATH=/usr/bin:/bin HOME=/tmp "$B/bin/python3" -m compileall -q -j0 \
    "$B/lib/python3.11" "$B/lib/python3/dist-packages" >/dev/null

# ---- 7. check it in an empty environment: a LocalCluster, and nothing loaded from outside it
cat > "$WORK/check.py" <<'EOF'
import os, sys
import psutil, xxhash, cloudpickle
from distributed import Client, LocalCluster
home = os.path.realpath(os.environ.get("PYTHONHOME") or sys.prefix)
def outside():
    import os, sys
    return sorted(m.__file__ for m in list(sys.modules.values())
                  if getattr(m, "__file__", None) and not os.path.realpath(m.__file__).startswith(home + "/")
                  and m.__name__ not in ("__main__", "__mp_main__"))
def env_of_child():
    import subprocess
    return subprocess.run(["/usr/bin/env"], capture_output=True, text=True).stdout
if __name__ == "__main__":
    cluster = LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=":0")
    client = Client(cluster)
    assert client.gather(client.map(lambda x: x * x, range(10))) == [x * x for x in range(10)]
    bad = outside() + [f for fl in client.run(outside).values() for f in fl] + client.run_on_scheduler(outside)
    child = list(client.run(env_of_child).values())[0]
    client.close(); cluster.close()
    print("sys.path:", sys.path)
    assert all(p.startswith(home) for p in sys.path if p and os.path.exists(p) and p != os.path.dirname(os.path.abspath(__file__))), sys.path
    assert not bad, bad
    assert "PYTHONHOME" not in child and home not in child, child
    print("ok: LocalCluster of 2 processes; every module from", home, "; children get the caller's environment")
EOF
(cd "$WORK" && env -i PATH=/usr/bin:/bin HOME=/tmp "$B/bin/python3" check.py)

# ---- 8. pack
tar -C "$(dirname "$B")" -czf "$B.tar.gz" "$(basename "$B")"
echo "bundle: $B ($(du -sh "$B" | cut -f1) unpacked)"
echo "tarball: $B.tar.gz $(stat -c %s "$B.tar.gz") bytes ($(du -h "$B.tar.gz" | cut -f1))"
echo "highest glibc symbol version needed (lib/fallback aside): $(for f in "$B/bin/python3.11" "$B"/lib/*.so* $(find "$B/lib" -name '*.so'); do
    objdump -T "$f"; done 2>/dev/null | grep -o 'GLIBC_[0-9.]*' | sort -uV | tail -1)"
