#!/usr/bin/env python3
"""Import circles between the files of each crate of the workspace.

Every `.rs` file under `crates/*/src` is a node. An edge `a -> b` means that file `a` names an item
of file `b` through a path of its own crate: a `use` declaration or an inline path starting with
`crate::`, `super::`, `self::` or a child module's name. Paths through a re-export (`pub use`)
are followed to the file that defines the item, and a re-export itself is not an edge (a facade
that re-exports its children does not depend on them in the sense that matters here) unless the file uses the re-exported name itself. Code inside `#[cfg(test)]` modules counts too, unless `--no-tests`.

Prints every strongly connected component of more than one file (an import circle) per crate, with
the edges inside it, and exits 1 if there is any; `--edges` prints every edge.

    python3 tools/file_cycles.py            # the whole workspace
    python3 tools/file_cycles.py crates/vr  # one crate

Regex-based (no macro expansion, no type inference): a path built inside a macro is not seen.
"""

import os
import re
import sys
from collections import defaultdict

IDENT = r"[A-Za-z_][A-Za-z0-9_]*"


def strip_comments_and_strings(src):
    """Blank out comments, string and char literals (keeps line structure)."""
    out = []
    i, n = 0, len(src)
    while i < n:
        c = src[i]
        if src.startswith("//", i):
            j = src.find("\n", i)
            j = n if j < 0 else j
            i = j
        elif src.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if src.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif src.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append("\n" * src.count("\n", i, j))
            i = j
        elif c == "r" and re.match(r'r#*"', src[i:i + 10]) and (i == 0 or not (src[i - 1].isalnum() or src[i - 1] == "_")):
            m = re.match(r'r(#*)"', src[i:])
            end = '"' + m.group(1)
            j = src.find(end, i + len(m.group(0)))
            j = n if j < 0 else j + len(end)
            out.append('""' + "\n" * src.count("\n", i, j))
            i = j
        elif c == '"':
            j = i + 1
            while j < n and src[j] != '"':
                j += 2 if src[j] == "\\" else 1
            out.append('""' + "\n" * src.count("\n", i, j))
            i = j + 1
        elif c == "'" and re.match(r"'(\\.|[^\\'])'", src[i:i + 4] + "    "):
            m = re.match(r"'(\\[^']*|[^\\'])'", src[i:])
            if m:
                out.append("' '")
                i += len(m.group(0))
            else:
                out.append(c)
                i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def expand_use_tree(tree):
    """`a::{b, c::{d, e}}` -> [['a','b'], ['a','c','d'], ['a','c','e']] (aliases removed first)."""
    tree = re.sub(r"\s+", "", tree)

    def parse(s, prefix):
        paths = []
        depth, start, i = 0, 0, 0
        parts = []
        for i, ch in enumerate(s):
            if ch == "{":
                depth += 1
            elif ch == "}":
                depth -= 1
            elif ch == "," and depth == 0:
                parts.append(s[start:i])
                start = i + 1
        parts.append(s[start:])
        for part in parts:
            if not part:
                continue
            if "{" in part:
                head, rest = part.split("{", 1)
                rest = rest[: rest.rfind("}")]
                head_segs = [x for x in head.split("::") if x]
                paths += parse(rest, prefix + head_segs)
            else:
                segs = [x for x in part.split("::") if x]
                paths.append(prefix + segs)
        return paths

    return parse(tree, [])


def use_paths(text):
    """Yield (is_pub_reexport, path segments, offset) for every `use` declaration."""
    for m in re.finditer(r"(?<![A-Za-z0-9_])(pub(\([^)]*\))?\s+)?use\s+([^;]+);", text):
        tree = re.sub(r"\s+as\s+" + IDENT, "", m.group(3))
        for p in expand_use_tree(tree):
            yield (m.group(1) is not None and (m.group(2) is None or "crate" in (m.group(2) or "") or "super" in (m.group(2) or "")), p, m.start())


class Crate:
    def __init__(self, root):
        self.root = root
        self.src = os.path.join(root, "src")
        self.files = {}  # module path tuple -> file
        self.inline = {}  # module path tuple -> (file, is_test) for inline modules
        self.children = defaultdict(set)  # module path -> child names
        self.texts = {}
        self.module_spans = {}  # file -> list of (start, end, modpath, is_test)
        entry = os.path.join(self.src, "lib.rs")
        if not os.path.exists(entry):
            entry = os.path.join(self.src, "main.rs")
        self.load(("crate",), entry)

    def load(self, modpath, path):
        if not os.path.exists(path):
            return
        self.files[modpath] = path
        text = strip_comments_and_strings(open(path, encoding="utf-8").read())
        self.texts[path] = text
        base = os.path.basename(path)
        if base in ("lib.rs", "main.rs", "mod.rs"):
            child_dir = os.path.dirname(path)
        else:
            child_dir = path[:-3]
        spans = [(0, len(text), modpath, False)]
        # inline modules (track braces)
        for m in re.finditer(r"(#\[cfg\(test\)\]\s*)?(pub(\([^)]*\))?\s+)?mod\s+(" + IDENT + r")\s*([;{])", text):
            name = m.group(4)
            if m.group(5) == ";":
                # a file module; only at the top level of this file (nested file modules are rare)
                owner = self.owner(spans, m.start())
                if owner[2] != modpath:
                    continue
                self.children[modpath].add(name)
                cand = [os.path.join(child_dir, name + ".rs"), os.path.join(child_dir, name, "mod.rs")]
                for c in cand:
                    if os.path.exists(c):
                        self.load(modpath + (name,), c)
                        break
            else:
                start = m.end() - 1
                depth, j = 0, start
                while j < len(text):
                    if text[j] == "{":
                        depth += 1
                    elif text[j] == "}":
                        depth -= 1
                        if depth == 0:
                            break
                    j += 1
                owner = self.owner(spans, m.start())
                inner = owner[2] + (name,)
                is_test = owner[3] or m.group(1) is not None
                spans.append((start, j, inner, is_test))
                self.inline[inner] = (path, is_test)
                self.children[owner[2]].add(name)
        self.module_spans[path] = spans

    @staticmethod
    def owner(spans, pos):
        best = spans[0]
        for s in spans[1:]:
            if s[0] <= pos <= s[1] and s[0] >= best[0]:
                best = s
        return best

    def file_of(self, modpath):
        if modpath in self.files:
            return self.files[modpath]
        if modpath in self.inline:
            return self.inline[modpath][0]
        return None

    def is_module(self, modpath):
        return modpath in self.files or modpath in self.inline

    def absolute(self, segs, here):
        """Path segments as written in module `here` -> absolute path from `crate`, or None."""
        if not segs:
            return None
        if segs[0] == "crate":
            return tuple(segs)
        if segs[0] in ("self", "super"):
            cur = list(here)
            i = 0
            while i < len(segs) and segs[i] in ("self", "super"):
                if segs[i] == "super":
                    if len(cur) == 1:
                        return None
                    cur.pop()
                i += 1
            return tuple(cur) + tuple(segs[i:])
        if segs[0] in self.children.get(here, ()):
            return tuple(here) + tuple(segs)
        return None

    def reexports(self, modpath):
        """name -> absolute path of `pub use` items of a module (and globs under '*')."""
        path = self.file_of(modpath)
        if path is None:
            return {}
        text = self.texts[path]
        spans = self.module_spans[path]
        out = defaultdict(list)
        for is_pub, segs, pos in use_paths(text):
            if not is_pub or self.owner(spans, pos)[2] != modpath:
                continue
            ab = self.absolute(segs, modpath)
            if ab is None:
                continue
            out[segs[-1]].append(ab)
        return out

    def resolve(self, ab, depth=0):
        """Absolute path -> the file that defines what it names (following re-exports)."""
        if depth > 20:
            return None
        # longest module prefix
        k = len(ab)
        while k > 0 and not self.is_module(ab[:k]):
            k -= 1
        if k == 0:
            return None
        mod = ab[:k]
        if k == len(ab) or ab[k] == "*":
            return self.file_of(mod)
        name = ab[k]
        rex = self.reexports(mod)
        if name in rex:
            for target in rex[name]:
                if target == ab:
                    continue
                f = self.resolve(target + ab[k + 1:] if target[-1] == name else target, depth + 1)
                if f:
                    return f
        for target in rex.get("*", []):
            sub = target[:-1] + (name,)
            f = self.resolve(sub, depth + 1)
            if f and f != self.file_of(mod):
                return f
        return self.file_of(mod)

    def edges(self, tests=True):
        edges = defaultdict(set)
        for path, text in self.texts.items():
            spans = self.module_spans[path]
            seen = set()
            code_without_uses = re.sub(r"(?<![A-Za-z0-9_])(pub(\([^)]*\))?\s+)?use\s+[^;]+;", " ", text)
            for is_pub, segs, pos in use_paths(text):
                own = self.owner(spans, pos)
                if is_pub and segs and segs[-1] != "*" and not re.search(r"\b" + re.escape(segs[-1]) + r"\b", code_without_uses):
                    continue  # a re-export that this file does not use itself
                if own[3] and not tests:
                    continue
                seen.add(pos)
                ab = self.absolute(segs, own[2])
                if ab is None:
                    continue
                f = self.resolve(ab)
                if f and f != path:
                    edges[path].add(f)
            for m in re.finditer(r"(?<![A-Za-z0-9_:])(" + IDENT + r"(?:::" + IDENT + r")+)", text):
                own = self.owner(spans, m.start())
                if own[3] and not tests:
                    continue
                # skip the ones inside use declarations (already handled)
                line_start = text.rfind(";", 0, m.start())
                if re.search(r"\buse\s", text[line_start + 1:m.start()]):
                    continue
                segs = m.group(1).split("::")
                if segs[0] not in ("crate", "super", "self") and segs[0] not in self.children.get(own[2], ()):
                    continue
                ab = self.absolute(segs, own[2])
                if ab is None:
                    continue
                f = self.resolve(ab)
                if f and f != path:
                    edges[path].add(f)
        return edges


def sccs(nodes, edges):
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def strong(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            out.append(comp)

    sys.setrecursionlimit(10000)
    for v in nodes:
        if v not in index:
            strong(v)
    return out


def main(argv):
    tests = "--no-tests" not in argv
    show_edges = "--edges" in argv
    roots = [a for a in argv if not a.startswith("--")]
    if not roots:
        roots = sorted(os.path.join("crates", d) for d in os.listdir("crates"))
    bad = 0
    for root in roots:
        if not os.path.exists(os.path.join(root, "src")):
            continue
        crate = Crate(root)
        edges = crate.edges(tests)
        nodes = sorted(crate.texts)
        if show_edges:
            for a in nodes:
                for b in sorted(edges.get(a, ())):
                    print(f"{a} -> {b}")
        for comp in sccs(nodes, edges):
            if len(comp) > 1:
                bad += 1
                comp = sorted(comp)
                print(f"circle in {root}: " + ", ".join(os.path.relpath(c, crate.src) for c in comp))
                for a in comp:
                    for b in sorted(edges.get(a, ())):
                        if b in comp:
                            print(f"    {os.path.relpath(a, crate.src)} -> {os.path.relpath(b, crate.src)}")
        print(f"{root}: {len(nodes)} files, {sum(len(v) for v in edges.values())} edges")
    print(f"{bad} import circle(s)" if bad else "no import circles")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
