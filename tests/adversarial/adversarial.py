#!/usr/bin/env python3
"""Measure how robust scanreg-cli is against hostile input, by category.

Areas: (1) mutated PCD and (2) mutated PLY scans read by `convert` / `new`+`info`; (3) mutated
project JSON read by `info` and `register`, (3b) mutated pose JSON read by `new --poses`; (4) special
files (FIFO, /dev/zero, directory, chmod 000) as project, pose or scan file; (5) outputs aimed at
inputs (merge/export/new/convert/report onto a scan or the project); (6) kill -9 during register /
merge / export-clouds; (7) nonsense options; (8) two concurrent `register` runs on one project.

Every child runs with RLIMIT_AS (--mem-gb), no core dumps and a timeout (--timeout). A failing case
prints one line (command, area, what happened, start of stderr); then a Markdown table counts per
area: crashes (signals), hangs (timeouts) / memory blow-ups (peak RSS over --rss-mb, bad_alloc /
out-of-memory messages), silently accepted bad data (exit 0 on certainly invalid input), data
destroyed (an input changed or removed, a project no longer loading) and other failures (leftover
`.tmp-` files after the next run, non-zero exit without a message). Failure lines quote stderr
without its "[info]" lines. Areas 4 and 5 run their fixed
list of cases; the others run --cases-per-area cases each. Exit status 0 (it is a measurement)
unless the script itself fails (2).

Run (from /work/main; use nice on a busy machine):
    nice -n 19 python3 tests/adversarial/adversarial.py --cases-per-area 100
    python3 tests/adversarial/adversarial.py --cases-per-area 3 --seed 7 --timeout 20 --keep
"""
import argparse, hashlib, json, os, random, re, resource, shlex, shutil, signal, stat, subprocess
import sys, tempfile, time, types

COLS = ("crash", "hang", "mem", "accepted", "destroyed", "other")
MEM_RE = re.compile(r"bad_alloc|cannot allocate memory|out of memory|MemoryError", re.I)
NOBODY = 65534


class Child:
    """One scanreg-cli process: own session, RLIMIT_AS, stdout/stderr to temporary files."""

    def __init__(self, ctx, args, cwd, nobody):
        self.ctx, self.argv = ctx, [ctx.cli] + [str(a) for a in args]
        self.err = tempfile.TemporaryFile()
        lim = ctx.mem_bytes

        def pre():
            resource.setrlimit(resource.RLIMIT_AS, (lim, lim))
            resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
            if nobody and os.geteuid() == 0:
                os.setgroups([]); os.setgid(NOBODY); os.setuid(NOBODY)
        self.t0 = time.monotonic()
        self.p = subprocess.Popen(self.argv, cwd=cwd or ctx.work, stdin=subprocess.DEVNULL,
                                  stdout=subprocess.DEVNULL, stderr=self.err, preexec_fn=pre,
                                  start_new_session=True)

    def wait(self, kill_after=None):
        timed_out = killed = False
        while True:
            pid, status, ru = os.wait4(self.p.pid, os.WNOHANG)
            if pid:
                break
            el = time.monotonic() - self.t0
            killed = kill_after is not None and el >= kill_after
            timed_out = not killed and el >= self.ctx.timeout
            if killed or timed_out:
                os.killpg(self.p.pid, signal.SIGKILL)
                pid, status, ru = os.wait4(self.p.pid, 0)
                break
            time.sleep(0.01)
        self.p.returncode = rc = os.waitstatus_to_exitcode(status)
        self.err.seek(0)
        err = self.err.read().decode("utf-8", "replace")
        self.err.close()
        return types.SimpleNamespace(argv=self.argv, rc=rc, timed_out=timed_out, killed=killed,
                                     rss_mb=ru.ru_maxrss / 1024.0, secs=time.monotonic() - self.t0, err=err)


class Ctx:
    def __init__(self, a):
        self.cli, self.timeout, self.n, self.rss_mb = a.cli, a.timeout, a.cases_per_area, a.rss_mb
        self.mem_bytes = int(a.mem_gb * 2**30)
        self.rng = random.Random(a.seed)
        self.work, self.verbose = a.work, a.verbose
        self.rows, self.failures, self.serial = {}, [], 0
        self.findings = None

    def start(self, *args, cwd=None, nobody=False):
        return Child(self, args, cwd, nobody)

    def run(self, *args, **kw):
        return self.start(*args, **kw).wait()

    def show(self, argv):
        return shlex.join(argv).replace(self.work, "$W")

    def case_dir(self, area, src=None):
        self.serial += 1
        d = os.path.join(self.work, "cases", f"{self.serial:04d}-" + re.sub(r"\W+", "-", area))
        shutil.copytree(src, d) if src else os.makedirs(d)
        return d

    # --- findings of the current case -------------------------------------------------------
    def begin(self, area):
        self.area, self.findings = area, []
        self.rows.setdefault(area, dict(cases=0, **{c: 0 for c in COLS}))

    def flag(self, kind, what, detail):
        self.findings.append((kind, what, detail))

    def check(self, res, invalid=False, need_msg=False):
        """Classify one run (flagging what went wrong); returns True when it exited 0."""
        cmd = self.show(res.argv)
        err = " ".join(l for l in res.err.splitlines() if not l.startswith("[info]"))[:200]
        if self.verbose:
            print(f"  [{self.area}] rc {res.rc} {res.secs:.1f} s {res.rss_mb:.0f} MB: {cmd}\n      {err}")
        if res.timed_out:
            self.flag("hang", cmd, f"timeout after {self.timeout:.0f} s; stderr: {err}")
        elif res.rss_mb > self.rss_mb or MEM_RE.search(res.err):
            self.flag("mem", cmd, f"rc {res.rc}, peak RSS {res.rss_mb:.0f} MB; stderr: {err}")
        elif res.rc < 0 and not res.killed:
            self.flag("crash", cmd, f"{signal.Signals(-res.rc).name}; stderr: {err}")
        elif res.rc == 0 and invalid:
            self.flag("accepted", cmd, f"exit 0 on invalid input ({invalid}); stderr: {err}")
        elif res.rc > 0 and need_msg and not res.err.strip():
            self.flag("other", cmd, f"exit {res.rc} without a message")
        return res.rc == 0 and not res.timed_out

    def end(self):
        row = self.rows[self.area]
        row["cases"] += 1
        for kind in {k for k, _, _ in self.findings}:
            row[kind] += 1
        for kind, what, detail in self.findings:
            line = f"FAIL [{self.area}] {kind}: {what}\n    -> {detail}"
            self.failures.append(line)
            print(line, flush=True)


def sha_tree(d):
    """sha256 of every regular file under d (the feature cache .scanreg-cache is left out)."""
    out = {}
    for root, dirs, files in os.walk(d):
        dirs[:] = [x for x in dirs if x != ".scanreg-cache"]
        for f in files:
            p = os.path.join(root, f)
            if stat.S_ISREG(os.lstat(p).st_mode):
                with open(p, "rb") as fh:
                    out[os.path.relpath(p, d)] = hashlib.sha256(fh.read()).hexdigest()
    return out


def changed(before, after, names=None):
    names = names if names is not None else before
    return [n for n in names if before.get(n) != after.get(n)]


def tmp_leftovers(d):
    return [os.path.join(r, f) for r, ds, fs in os.walk(d) for f in fs + ds if ".tmp-" in f]


# --- scan-file mutators: fn(data, rng) -> (bytes, certainly_invalid) ----------------------------
def split_header(data, marker):
    i = data.index(marker)
    j = data.index(b"\n", i + 1) + 1
    return data[:j], data[j:]


def hsub(data, marker, pat, repl):
    h, body = split_header(data, marker)
    return re.sub(pat, repl, h, count=1, flags=re.M) + body


def bitflips(data, r, start):
    b = bytearray(data)
    for _ in range(r.randint(1, 40)):
        b[r.randrange(start, len(b))] ^= 1 << r.randrange(8)
    return bytes(b)


def pcd_mutators():
    M = b"\nDATA "
    hl = lambda d: len(split_header(d, M)[0])
    return [
        ("truncated data", lambda d, r: (d[:r.randrange(hl(d), len(d) - 1)], True)),
        ("header only", lambda d, r: (split_header(d, M)[0], True)),
        ("empty file", lambda d, r: (b"", True)),
        ("POINTS/WIDTH 4e9", lambda d, r: (hsub(hsub(d, M, rb"^WIDTH .*$", b"WIDTH 4000000000"),
                                                 M, rb"^POINTS .*$", b"POINTS 4000000000"), True)),
        ("WIDTH*HEIGHT != POINTS", lambda d, r: (hsub(d, M, rb"^WIDTH .*$", b"WIDTH 201"), True)),
        ("negative WIDTH", lambda d, r: (hsub(d, M, rb"^WIDTH .*$", b"WIDTH -200"), True)),
        ("SIZE 0", lambda d, r: (hsub(d, M, rb"^SIZE .*$", b"SIZE 0 0 0 0"), True)),
        ("TYPE bogus", lambda d, r: (hsub(d, M, rb"^TYPE .*$", b"TYPE Q F F F"), True)),
        ("no x y z", lambda d, r: (hsub(d, M, rb"^FIELDS .*$", b"FIELDS a b c intensity"), True)),
        ("FIELDS/SIZE count mismatch", lambda d, r: (hsub(d, M, rb"^FIELDS .*$", b"FIELDS x y z"), True)),
        ("COUNT huge", lambda d, r: (hsub(d, M, rb"^COUNT .*$", b"COUNT 1000000 1 1 1"), True)),
        ("DATA ascii, binary body", lambda d, r: (hsub(d, M, rb"^DATA .*$", b"DATA ascii"), True)),
        ("DATA binary_compressed bogus", lambda d, r: (hsub(d, M, rb"^DATA .*$", b"DATA binary_compressed"), True)),
        ("bit flips in data", lambda d, r: (bitflips(d, r, hl(d)), False)),
        ("bit flips anywhere", lambda d, r: (bitflips(d, r, 0), False)),
        ("all NaN/Inf values", lambda d, r: (d[:hl(d)] + b"\x00\x00\xc0\x7f\x00\x00\x80\x7f"
                                              * ((len(d) - hl(d)) // 8), False)),
        ("1 MB comment line", lambda d, r: (b"# " + b"x" * 2**20 + b"\n" + d, False)),
        ("trailing garbage", lambda d, r: (d + os.urandom(r.randint(1, 5000)), False)),
    ]


def ply_layout(d):
    h, body = split_header(d, b"end_header")
    sizes = dict(char=1, uchar=1, int8=1, uint8=1, short=2, ushort=2, int16=2, uint16=2, int=4,
                 uint=4, int32=4, uint32=4, float=4, float32=4, double=8, float64=8)
    nvert, rec, elem = 0, 0, None
    for line in h.decode("latin-1").splitlines():
        w = line.split()
        if w[:1] == ["element"]:
            elem = w[1]
            nvert = int(w[2]) if elem == "vertex" else nvert
        elif w[:1] == ["property"] and elem == "vertex":
            rec += sizes[w[1]]
    grid, entries, i = len(h) + nvert * rec, [], len(h) + nvert * rec
    while i < len(d):
        if d[i]:
            entries.append(i)
        i += 1 + 4 * d[i]
    return len(h), grid, entries


def ply_set_index(d, r, value):
    _, _, entries = ply_layout(d)
    i = r.choice(entries)
    return d[:i + 1] + value.to_bytes(4, "little", signed=True) + d[i + 5:]


def ply_mutators():
    M = b"end_header"
    hl = lambda d: ply_layout(d)[0]
    return [
        ("truncated body", lambda d, r: (d[:r.randrange(hl(d), len(d) - 1)], True)),
        ("empty file", lambda d, r: (b"", True)),
        ("vertex count 4e9", lambda d, r: (hsub(d, M, rb"^element vertex .*$", b"element vertex 4000000000"), True)),
        ("vertex count negative", lambda d, r: (hsub(d, M, rb"^element vertex .*$", b"element vertex -5"), True)),
        ("grid index out of range", lambda d, r: (ply_set_index(d, r, 99999999), True)),
        ("grid index negative", lambda d, r: (ply_set_index(d, r, -7), True)),
        ("grid list count 255", lambda d, r: ((lambda i: d[:i] + b"\xff" + d[i + 1:])(r.choice(ply_layout(d)[2])), True)),
        ("format ascii, binary body", lambda d, r: (hsub(d, M, rb"^format .*$", b"format ascii 1.0"), True)),
        ("format big endian", lambda d, r: (hsub(d, M, rb"^format .*$", b"format binary_big_endian 1.0"), True)),
        ("no end_header", lambda d, r: (d.replace(b"end_header\n", b"end_headr\n", 1), True)),
        ("unknown property type", lambda d, r: (d.replace(b"property double x", b"property quux x", 1), True)),
        ("no x property", lambda d, r: (d.replace(b"property double x", b"property double q", 1), True)),
        ("NaN pose in header", lambda d, r: (re.sub(rb"scanreg_world_from_scan 1 ", b"scanreg_world_from_scan nan ", d, 1), True)),
        ("num_cols 4e9", lambda d, r: (hsub(d, M, rb"^obj_info num_cols .*$", b"obj_info num_cols 4000000000"), False)),
        ("bit flips in body", lambda d, r: (bitflips(d, r, hl(d)), False)),
        ("bit flips anywhere", lambda d, r: (bitflips(d, r, 0), False)),
        ("trailing garbage", lambda d, r: (d + os.urandom(r.randint(1, 5000)), False)),
    ]


# --- JSON mutators: fn(doc, text, rng) -> (text, certainly_invalid) ------------------------------
def items(doc):
    return doc["scans"] if "scans" in doc else doc["poses"]


def with_item(fn, certain=True):
    def m(doc, text, r):
        fn(r.choice(items(doc)), r)
        return json.dumps(doc, indent=1), certain
    return m


def json_mutators(project):
    def deep(doc, t, r):
        return "[" * 200000 + "]" * 200000, True

    def dup(doc, t, r):
        it = items(doc)
        key = "name" if "name" in it[0] else "scan"
        it[1][key] = it[0][key]
        return json.dumps(doc), True

    def setdoc(fn, certain=True):
        return lambda doc, t, r: (fn(doc) or json.dumps(doc), certain)

    def nonrigid(s, r):
        s["world_from_scan"] = [v * 1000 if i in (0, 1, 2, 4, 5, 6, 8, 9, 10) else v
                                for i, v in enumerate(s["world_from_scan"])]

    ms = [
        ("truncated", lambda doc, t, r: (t[:r.randrange(1, len(t) - 1)], True)),
        ("empty", lambda doc, t, r: ("", True)),
        ("200000-deep nesting", deep),
        ("matrix of 15", with_item(lambda s, r: s.update(world_from_scan=s["world_from_scan"][:15]))),
        ("matrix entry string", with_item(lambda s, r: s["world_from_scan"].__setitem__(r.randrange(16), "abc"))),
        ("matrix NaN literal", with_item(lambda s, r: s["world_from_scan"].__setitem__(3, float("nan")))),
        ("matrix Infinity literal", with_item(lambda s, r: s["world_from_scan"].__setitem__(0, float("inf")))),
        ("matrix scaled x1000", with_item(nonrigid)),
        ("duplicate scan name", dup),
        ("list is a string", setdoc(lambda d: d.update({"scans" if "scans" in d else "poses": "hello"}))),
        ("bit flips", lambda doc, t, r: (bitflips(t.encode(), r, 0).decode("latin-1"), False)),
        ("key deleted", with_item(lambda s, r: s.pop(r.choice(sorted(s))), False)),
        ("5 MB name", with_item(lambda s, r: s.update({"name" if "name" in s else "scan": "x" * 5_000_000}), False)),
    ]
    if project:
        ms += [
            ("link to ghost scan", setdoc(lambda d: d["links"][0].update(parent="ghost"))),
            ("root is ghost", setdoc(lambda d: d.update(root="ghost"))),
            ("index_in_file bad", with_item(lambda s, r: s.update(index_in_file=r.choice([-1, 7, 2**40])))),
            ("path /etc/passwd", with_item(lambda s, r: s.update(path="../" * 12 + "etc/passwd"))),
            ("registered is a string", with_item(lambda s, r: s.update(registered="yes"))),
            ("schema_version 999", setdoc(lambda d: d.update(schema_version=999), False)),
        ]
    else:
        ms += [("version 99", setdoc(lambda d: d.update(version=99), False))]
    return ms


def pick(ctx, key, lst, k, order={}):
    """The k-th of a shuffled list (per key), so that a few cases cover different mutations."""
    if key not in order:
        order[key] = ctx.rng.sample(lst, len(lst))
    return order[key][k % len(lst)]


# --- areas ---------------------------------------------------------------------------------------
def area_clouds(ctx, area, seed_file, mutators, ext):
    seed = open(seed_file, "rb").read()
    for k in range(ctx.n):
        name, fn = pick(ctx, area, mutators, k)
        data, certain = fn(seed, ctx.rng)
        ctx.begin(area)
        d = ctx.case_dir(area)
        src = os.path.join(d, "in" + ext)
        open(src, "wb").write(data)
        before = sha_tree(d)
        why = name if certain else False
        if k % 2 == 0:
            ctx.check(ctx.run("convert", src, os.path.join(d, "out.ptx")), invalid=why, need_msg=True)
        elif ctx.check(ctx.run("new", os.path.join(d, "n.scanreg.json"), src), invalid=why, need_msg=True):
            ctx.check(ctx.run("info", os.path.join(d, "n.scanreg.json")))
        if changed(before, sha_tree(d)):
            ctx.flag("destroyed", f"{name} ({ext})", f"input changed/removed: {changed(before, sha_tree(d))}")
        ctx.end()


def area_json(ctx, area, project):
    for k in range(ctx.n):
        ctx.begin(area)
        d = ctx.case_dir(area, ctx.reg)
        target = os.path.join(d, "project.scanreg.json" if project else "poses.json")
        name, fn = pick(ctx, area, json_mutators(project), k)
        doc = json.load(open(ctx.proj if project else ctx.poses))
        text, certain = fn(doc, json.dumps(doc, indent=1), ctx.rng)
        open(target, "w", encoding="latin-1", errors="replace").write(text)
        why = name if certain else False
        scans = sorted(n for n in sha_tree(d) if n.endswith(".ptx"))
        before = sha_tree(d)
        if project:
            ctx.check(ctx.run("info", target), invalid=why, need_msg=True)
            ok = ctx.check(ctx.run("register", target), invalid=why, need_msg=True)
            after = sha_tree(d)
            bad = changed(before, after, scans + ([] if ok else ["project.scanreg.json"]))
            if ok and ctx.run("info", target).rc != 0:
                bad.append("project no longer loads after register exit 0")
        else:
            newp = os.path.join(d, "n.scanreg.json")
            if ctx.check(ctx.run("new", newp, *[os.path.join(d, s) for s in scans], "--poses", target),
                         invalid=why, need_msg=True):
                ctx.check(ctx.run("info", newp))
            bad = changed(before, sha_tree(d), scans + ["poses.json", "project.scanreg.json"])
        if bad:
            ctx.flag("destroyed", f"{name} ({os.path.basename(target)})", f"{bad}")
        ctx.end()


def area_special(ctx, area):
    def setup(kind, d):
        p = os.path.join(d, {"fifo": "f.scanreg.json", "zero": "z.scanreg.json", "zpose": "z.json",
                             "zscan": "z.pcd", "fscan": "f.ply", "dir": "d.scanreg.json",
                             "urandom": "u.scanreg.json"}.get(kind, "project.scanreg.json"))
        if kind in ("fifo", "fscan"):
            os.mkfifo(p)
        elif kind in ("zero", "zpose", "zscan"):
            os.symlink("/dev/zero", p)
        elif kind == "urandom":
            os.symlink("/dev/urandom", p)
        elif kind == "dir":
            os.makedirs(p)
        elif kind in ("chmod-project", "chmod-scan"):
            for r, ds, fs in os.walk(d):
                for f in ds + fs + ["."]:
                    os.chown(os.path.join(r, f), NOBODY, NOBODY) if os.geteuid() == 0 else None
            p = p if kind == "chmod-project" else os.path.join(d, "s01.ptx")
            os.chmod(p, 0)
        return os.path.join(d, "project.scanreg.json"), p

    cases = [("fifo", "info {p}"), ("fifo", "register {p}"), ("zero", "info {p}"),
             ("zero", "register {p}"), ("urandom", "info {p}"), ("zpose", "new {d}/n.scanreg.json {d}/s01.ptx --poses {p}"),
             ("zscan", "convert {p} {d}/o.ptx"), ("fscan", "convert {p} {d}/o.ptx"), ("dir", "info {p}"),
             ("dir", "register {p}"), ("chmod-project", "info {p}"), ("chmod-project", "register {p}"),
             ("chmod-scan", "register {P}")]
    for kind, cmd in cases:
        ctx.begin(area)
        d = ctx.case_dir(area, ctx.reg)
        os.chmod(d, 0o755)
        P, p = setup(kind, d)
        before = sha_tree(d)
        args = [t.format(p=p, d=d, P=P) for t in cmd.split()]
        ctx.check(ctx.run(*args, nobody=kind.startswith("chmod")), invalid=kind, need_msg=True)
        if changed(before, sha_tree(d)):
            ctx.flag("destroyed", ctx.show(args), f"changed: {changed(before, sha_tree(d))}")
        ctx.end()


def area_overwrite(ctx, area):
    cases = ["merge {P} --voxel 0.3 --method tsdf --out {d}/s01.ptx",
             "merge {P} --voxel 0.3 --method tsdf --out {d}/m.ply --points {d}/s02.ptx",
             "merge {P} --voxel 0.3 --method tsdf --out {P}",
             "export-poses {P} --format json --out {P}", "export-poses {P} --format csv --out {d}/s01.ptx",
             "export-poses {P} --format txt --out {P}", "new {d}/s01.ptx {d}/s01.ptx {d}/s02.ptx",
             "new {d}/s02.ptx {d}/s01.ptx", "export-clouds {P} --out {d}", "export-clouds {P} --out {P}",
             "export-clouds {P} --out {d} --format ptx --apply-poses", "convert {d}/s01.ptx {d}/s01.ptx",
             "report {P} --out {P}"]
    for cmd in cases:
        ctx.begin(area)
        d = ctx.case_dir(area, ctx.reg)
        args = [t.format(P=os.path.join(d, "project.scanreg.json"), d=d) for t in cmd.split()]
        before = sha_tree(d)
        ctx.check(ctx.run(*args), invalid="output onto an input", need_msg=True)
        bad = changed(before, sha_tree(d))
        if bad:
            ctx.flag("destroyed", ctx.show(args), f"inputs changed/removed: {bad}")
        ctx.end()


def after_abuse(ctx, d, scans_before, label, rerun=None):
    """The project must load (the next run) and leave no .tmp- files. rerun: the killed command,
    run again to completion first (a temporary in an output folder goes at the next write there)."""
    P = os.path.join(d, "project.scanreg.json")
    if rerun:
        ctx.check(ctx.run(*rerun))
    res = ctx.run("info", P)
    ctx.check(res)
    if res.rc != 0:
        ctx.flag("destroyed", label, f"project no longer loads: {res.err.strip()[:200]}")
    bad = changed(scans_before, sha_tree(d), [n for n in scans_before if n.endswith(".ptx")])
    if bad:
        ctx.flag("destroyed", label, f"scan files changed/removed: {bad}")
    left = tmp_leftovers(d)
    if left:
        ctx.flag("other", label, f".tmp- files left after the next run: {[os.path.relpath(x, d) for x in left]}")


def area_kill(ctx, area):
    jobs = [("register", ctx.plain, ["register", "{P}"]),
            ("merge", ctx.reg, ["merge", "{P}", "--voxel", "0.2", "--method", "tsdf", "--out", "{d}/m.ply"]),
            ("export-clouds", ctx.reg, ["export-clouds", "{P}", "--out", "{d}/clouds"])]
    for k in range(ctx.n):
        name, src, tmpl = jobs[k % len(jobs)]
        ctx.begin(area)
        d = ctx.case_dir(area, src)
        P = os.path.join(d, "project.scanreg.json")
        args = [a.replace("{P}", P).replace("{d}", d) for a in tmpl]
        delay = ctx.rng.uniform(0.02, 0.9 * ctx.durations[name])  # usually before it ends
        before = sha_tree(d)
        res = ctx.start(*args).wait(kill_after=delay)
        ctx.check(res)
        after_abuse(ctx, d, before, f"{ctx.show(args)} (kill -9 after {delay:.2f} s)", rerun=args)
        ctx.end()


NONSENSE = [  # (arguments, certainly invalid?)  {P} registered project, {d} case folder
    ("simulate --out {d}/s --size 1000000x1000000", False), ("simulate --out {d}/s --size 0x0", True),
    ("simulate --out {d}/s --size -200x50", True), ("simulate --out {d}/s --size nanx50", True),
    ("simulate --out {d}/s --size 200x50x3", True), ("simulate --out {d}/s --size 200", True),
    ("simulate --out {d}/s --stations 0 --size 200x50", True),
    ("simulate --out {d}/s --stations -1 --size 200x50", True),
    ("simulate --out {d}/s --stations 1000000000 --size 200x50", False),
    ("simulate --out {d}/s --noise -1 --stations 2 --size 200x50", True),
    ("simulate --out {d}/s --noise nan --stations 2 --size 200x50", True),
    ("simulate --out {d}/s --spacing inf --stations 2 --size 200x50", True),
    ("simulate --out {d}/s --traffic -3 --stations 2 --size 200x50", True),
    ("simulate --out {d}/s --scene moon --stations 2 --size 200x50", True),
    ("merge {P} --out {d}/m.ply --voxel 1e-6", False), ("merge {P} --out {d}/m.ply --voxel 0", True),
    ("merge {P} --out {d}/m.ply --voxel -0.1", True), ("merge {P} --out {d}/m.ply --voxel nan", True),
    ("merge {P} --out {d}/m.ply --voxel inf", True), ("merge {P} --out {d}/m.ply --voxel 1e9", False),
    ("merge {P} --out {d}/m.ply --voxel 0.2 --sigma 1e300", False),
    ("merge {P} --out {d}/m.ply --voxel 0.2 --sigma -1", True),
    ("merge {P} --out {d}/m.ply --voxel 0.2 --sigma nan", True),
    ("merge {P} --out {d}/m.ply --voxel 0.2 --smooth -1", True),
    ("merge {P} --out {d}/m.ply --voxel 0.2 --method tsdf --smooth 1000000000", False),
    ("merge {P} --out {d}/m.ply --voxel 0.2 --max-range -5", True),
    ("merge {P} --out {d}/m.ply --voxel 0.2 --max-range nan", True),
    ("merge {P} --out {d}/m.ply --voxel 0.2 --max-memory -1", True),
    ("merge {P} --out {d}/m.ply --voxel 1e-4", False), ("merge {P} --out {d}/m.ply --max-memory 1e6", False),
    ("merge {P} --out {d}/m.ply --method foo", True), ("merge {P} --out {d}/m.ply --voxel", True),
    ("merge {P} --out {d}/m.xyz --voxel 0.2", True), ("merge {P} --out {d}/m.ply --voxel 0.2 --voxel -1", True),
    ("register {P} --ratio nan", True), ("register {P} --ratio -1", True), ("register {P} --ratio 5", False),
    ("register {P} --overlap-distance -1", True), ("register {P} --overlap-distance nan", True),
    ("register {P} --overlap-distance 1e300", False), ("register {P} --overlap-distance 1e-12", False),
    ("register {P} --noise -1", True), ("register {P} --noise nan", True), ("register {P} --root nosuch", True),
    ("register {P} --parent s01=nosuch", True), ("register {P} --parent s01=s01", True),
    ("register {P} --parent garbage", True), ("register {P} --coarse bogus", True),
    ("register {P} --fine bogus", True), ("register {P} --frobnicate", True), ("info {P} --frobnicate", True),
    ("export-poses {P} --format yaml --out {d}/a", True), ("export-clouds {P} --out {d}/e --format xyz", True),
    ("frobnicate {P}", True), ("convert {d}/s01.ptx {d}/o.ply --scan nosuch", False),
]


def area_options(ctx, area):
    for k in range(ctx.n):
        cmd, invalid = pick(ctx, area, NONSENSE, k)
        ctx.begin(area)
        d = ctx.case_dir(area, ctx.reg)
        P = os.path.join(d, "project.scanreg.json")
        args = [t.format(P=P, d=d) for t in cmd.split()]
        before = sha_tree(d)
        ok = ctx.check(ctx.run(*args), invalid=invalid and "nonsense option", need_msg=True)
        bad = changed(before, sha_tree(d), [n for n in before if n != "project.scanreg.json" or not ok])
        res = ctx.run("info", P)
        if bad or res.rc != 0:
            ctx.flag("destroyed", ctx.show(args), f"changed: {bad}; info rc {res.rc}")
        ctx.end()


def area_concurrent(ctx, area):
    for k in range(ctx.n):
        ctx.begin(area)
        d = ctx.case_dir(area, ctx.plain)
        P = os.path.join(d, "project.scanreg.json")
        before = sha_tree(d)
        first = ctx.start("register", P)
        time.sleep(ctx.rng.uniform(0.0, 0.5 * ctx.durations["register"]))
        second = ctx.start("register", P)
        r1, r2 = first.wait(), second.wait()
        ctx.check(r1)
        ctx.check(r2, need_msg=True)
        after_abuse(ctx, d, before, f"2 x {ctx.show(r1.argv)} at once (exits {r1.rc}, {r2.rc})")
        ctx.end()


def setup(ctx):
    def must(*args, cwd=None):
        t0 = time.monotonic()
        res = ctx.run(*args, cwd=cwd)
        if res.rc != 0:
            sys.exit(f"setup failed: {ctx.show(res.argv)}: rc {res.rc}: {res.err[:500]}")
        return time.monotonic() - t0
    w = ctx.work
    must("simulate", "--stations", "2", "--size", "200x50", "--seed", "1", "--out", f"{w}/plain")
    shutil.copytree(f"{w}/plain", f"{w}/reg")
    ctx.plain, ctx.reg, ctx.proj = f"{w}/plain", f"{w}/reg", f"{w}/reg/project.scanreg.json"
    ctx.durations = {"register": must("register", ctx.proj)}
    ctx.poses = f"{w}/poses.json"
    must("export-poses", ctx.proj, "--format", "json", "--out", ctx.poses)
    tmp = f"{w}/timing"
    shutil.copytree(ctx.reg, tmp)
    ctx.durations["merge"] = must("merge", f"{tmp}/project.scanreg.json", "--voxel", "0.2", "--method",
                                  "tsdf", "--out", f"{tmp}/m.ply")
    ctx.durations["export-clouds"] = must("export-clouds", f"{tmp}/project.scanreg.json", "--out", f"{tmp}/c")
    must("convert", f"{w}/plain/s01.ptx", f"{w}/seed.pcd")
    must("convert", f"{w}/plain/s01.ptx", f"{w}/seed.ply")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cli", default="/work/main/build/app/scanreg-cli")
    ap.add_argument("--cases-per-area", type=int, default=5)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=20.0, help="seconds per command")
    ap.add_argument("--mem-gb", type=float, default=4.0, help="RLIMIT_AS of each child")
    ap.add_argument("--rss-mb", type=float, default=2048.0, help="peak RSS counted as a memory blow-up")
    ap.add_argument("--work", help="work folder (default: a new one under /dev/shm)")
    ap.add_argument("--keep", action="store_true", help="keep the work folder")
    ap.add_argument("-v", "--verbose", action="store_true", help="print every checked command")
    a = ap.parse_args()
    if not os.access(a.cli, os.X_OK):
        sys.exit(f"not executable: {a.cli}")
    a.cli = os.path.abspath(a.cli)
    created = a.work is None
    a.work = os.path.abspath(a.work or tempfile.mkdtemp(prefix="scanreg-adv-", dir="/dev/shm"))
    os.makedirs(a.work, exist_ok=True)
    os.chmod(a.work, 0o755)  # the chmod-000 cases run as nobody
    ctx, t0 = Ctx(a), time.monotonic()
    try:
        setup(ctx)
        area_clouds(ctx, "1 PCD", f"{ctx.work}/seed.pcd", pcd_mutators(), ".pcd")
        area_clouds(ctx, "2 PLY", f"{ctx.work}/seed.ply", ply_mutators(), ".ply")
        area_json(ctx, "3 project JSON", True)
        area_json(ctx, "3b pose JSON", False)
        area_special(ctx, "4 special files")
        area_overwrite(ctx, "5 output onto input")
        area_kill(ctx, "6 kill -9")
        area_options(ctx, "7 nonsense options")
        area_concurrent(ctx, "8 concurrent register")
    finally:
        if created and not a.keep:
            shutil.rmtree(a.work, ignore_errors=True)
    print(f"\n{sum(r['cases'] for r in ctx.rows.values())} cases, {len(ctx.failures)} failures, "
          f"{time.monotonic() - t0:.0f} s (seed {a.seed}, timeout {a.timeout:.0f} s)\n")
    print("| area | cases | crashes | hangs / memory | silently accepted | data destroyed | other |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for area, r in ctx.rows.items():
        print(f"| {area} | {r['cases']} | {r['crash']} | {r['hang']} / {r['mem']} | {r['accepted']} "
              f"| {r['destroyed']} | {r['other']} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
