"""prt_provenance: reading a pool's sections and provenance (formats/POOL.md), hashing inputs, and
deciding whether an output is current (issue 21). Standard library only, plus python3-xxhash for
the content hashes when it is installed (hashlib's SHA-256 otherwise).

Used by scripts/prt-batch (the skip decision: `current_reason`, a chain at the end of the
provenance) and scripts/prt-bake (a pool's sections, their checksums and provenance; `step_reason`,
one step anywhere in the provenance and the steps it depends on).

How a batch recognises its own result: every tool built on prt::tool::PoolStep takes
`--provenance-tag JSON` and records that value as "tag" in its provenance parameters. prt-batch
passes each step a tag naming the input's content hash and the arguments of the chain of steps
up to it (`chain_tag`); an output is current (`current_reason` returns None) when its provenance
ends with the expected tools, at the expected versions, each carrying the expected tag.
"""
import hashlib
import json
import os
import struct

try:
    import xxhash  # python3-xxhash
except ImportError:  # pragma: no cover - depends on the machine
    xxhash = None

# Pool layout (formats/POOL.md): 64-byte header, then a table of 64-byte section entries.
MAGIC = b"PRTPOOL\0"
HEADER_BYTES = 64
ENTRY_BYTES = 64
MAX_SECTIONS = 4096
S_PROVENANCE = 1


class PoolError(Exception):
    """A file that cannot be read as a pool; the message names the file and the problem."""


def read_table(path):
    """The section table of the pool at `path`: a list of (type, version, offset, size)."""
    table, count = _raw_table(path)
    return [struct.unpack_from("<IIQQ", table, ENTRY_BYTES * i) for i in range(count)]


def read_checksums(path):
    """{section type: XXH3-64 of its payload} from the section table of the pool at `path` (the
    checksum each entry carries, formats/POOL.md; nothing is hashed here)."""
    table, count = _raw_table(path)
    return {struct.unpack_from("<I", table, ENTRY_BYTES * i)[0]:
            "%016x" % struct.unpack_from("<Q", table, ENTRY_BYTES * i + 40)[0] for i in range(count)}


def _raw_table(path):
    """The section table's bytes and its entry count."""
    try:
        with open(path, "rb") as f:
            head = f.read(HEADER_BYTES)
            if len(head) < HEADER_BYTES or head[:8] != MAGIC:
                raise ValueError("not a pool file (bad magic)")
            count = struct.unpack_from("<I", head, 24)[0]
            table_offset = struct.unpack_from("<Q", head, 32)[0]
            if count > MAX_SECTIONS:
                raise ValueError("section count %d" % count)
            f.seek(table_offset)
            table = f.read(ENTRY_BYTES * count)
            if len(table) != ENTRY_BYTES * count:
                raise ValueError("truncated section table")
    except (OSError, ValueError) as e:
        raise PoolError("%s: cannot read the pool: %s" % (path, e))
    return table, count


def read_sections(path, skip=(S_PROVENANCE,)):
    """{section type: payload bytes} of every section of the pool at `path` except those in
    `skip` (by default the provenance, whose entries carry the time they were written): two
    pools with equal results compare equal."""
    out = {}
    with open(path, "rb") as f:
        for stype, _version, offset, size in read_table(path):
            if stype in skip:
                continue
            f.seek(offset)
            data = f.read(size)
            if len(data) != size:
                raise PoolError("%s: section %d is truncated" % (path, stype))
            out[stype] = data
    return out


def read_provenance(path):
    """The provenance of the pool at `path`: the JSON list of {tool, version, parameters, time},
    oldest first ([] when the pool has none). Raises PoolError for a file that is not a pool."""
    for stype, _version, offset, size in read_table(path):
        if stype != S_PROVENANCE:
            continue
        try:
            with open(path, "rb") as f:
                f.seek(offset)
                provenance = json.loads(f.read(size).decode("utf-8"))
        except (OSError, ValueError, UnicodeDecodeError) as e:  # JSONDecodeError is a ValueError
            raise PoolError("%s: cannot read the provenance: %s" % (path, e))
        if not isinstance(provenance, list):
            raise PoolError("%s: the provenance is not a JSON list" % path)
        return provenance
    return []


def hash_name():
    """The content hash used here: "xxh3_64" (python3-xxhash), else "sha256"."""
    return "xxh3_64" if xxhash is not None else "sha256"


def file_hash(path, block=1 << 22):
    """"NAME:HEX", the content hash of the file at `path` (hash_name(); read in 4 MiB blocks)."""
    h = xxhash.xxh3_64() if xxhash is not None else hashlib.sha256()
    with open(path, "rb") as f:
        while True:
            chunk = f.read(block)
            if not chunk:
                break
            h.update(chunk)
    return "%s:%s" % (hash_name(), h.hexdigest())


def json_text(value):
    """`value` as compact JSON text with sorted keys (what a tool's --provenance-tag takes)."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"))


def chain_tag(input_hash, steps, args, maker="batch"):
    """The tag a script records with the last of `steps` (tool names, in order): the input's
    content hash and each step's extra arguments (`args`: tool -> list of strings; a file argument
    given as its content hash). Thread counts and file names are left out: they do not change the
    result. `maker`: "batch" (prt-batch: {"batch": "prt-batch", ...}) or "bake" (prt-bake)."""
    return {
        maker: "prt-" + maker,
        "input": input_hash,
        "steps": list(steps),
        "args": {s: list(args.get(s, [])) for s in steps},
    }


def current_reason(path, expected):
    """Why the pool at `path` is not the result `expected` describes, or None when it is.

    `expected` is the chain of steps, oldest first, each a dict {tool, version, tag}: the pool's
    provenance must end with these tools, written by these versions, each entry's parameters
    holding this tag (version None: any version)."""
    if not os.path.exists(path):
        return "no output yet"
    try:
        provenance = read_provenance(path)
    except PoolError as e:
        return str(e)
    if len(provenance) < len(expected):
        return "its provenance has %d steps, the chain has %d" % (len(provenance), len(expected))
    tail = provenance[len(provenance) - len(expected):]
    for got, want in zip(tail, expected):
        if not isinstance(got, dict) or got.get("tool") != want["tool"]:
            return "its provenance does not end with %s" % ", ".join(w["tool"] for w in expected)
        if want.get("version") is not None and got.get("version") != want["version"]:
            return "%s was version %s, now %s" % (want["tool"], got.get("version"), want["version"])
        params = got.get("parameters")
        tag = params.get("tag") if isinstance(params, dict) else None
        if tag != want["tag"]:
            if isinstance(tag, dict) and isinstance(want["tag"], dict) and tag.get("input") != want["tag"].get("input"):
                return "the input changed (content hash differs)"
            return "%s ran with other parameters" % want["tool"]
    return None


def entry_tag(entry):
    """The "tag" a provenance entry's parameters hold (--provenance-tag), or None."""
    params = entry.get("parameters") if isinstance(entry, dict) else None
    if isinstance(params, str):  # older writers kept parameters as JSON text
        try:
            params = json.loads(params)
        except ValueError:
            params = None
    return params.get("tag") if isinstance(params, dict) else None


def last_entry(provenance, tools):
    """Index of the newest entry of `provenance` written by one of `tools` (a name or a list), or -1."""
    names = [tools] if isinstance(tools, str) else list(tools)
    for i in range(len(provenance) - 1, -1, -1):
        if isinstance(provenance[i], dict) and provenance[i].get("tool") in names:
            return i
    return -1


def step_reason(provenance, tool, tag, depends):
    """Whether `tool`'s result in a pool whose provenance is `provenance` is current for `tag`:
    returns (None, note) when it is, (reason, None) when it must run. prt-bake's rule:

    - the newest entry of `tool` must exist and no tool of `depends` may come after it;
    - its tag must equal `tag`; an entry with no tag at all was made without a tag (by hand):
      current, and the note says so.
    """
    mine = last_entry(provenance, tool)
    if mine < 0:
        return "the pool's provenance has no %s step" % tool, None
    newer = last_entry(provenance, depends)
    if newer > mine:
        return "%s ran after the last %s" % (provenance[newer].get("tool"), tool), None
    got = entry_tag(provenance[mine])
    if got is None:
        return None, "current (made without a provenance tag, by hand: kept; --force rebuilds)"
    if got == tag:
        return None, "current (same inputs and parameters)"
    if isinstance(got, dict) and isinstance(tag, dict) and got.get("input") != tag.get("input"):
        return "its input changed (content hash differs)", None
    return "%s ran with other inputs or parameters" % tool, None
