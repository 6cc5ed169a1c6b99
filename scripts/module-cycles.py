#!/usr/bin/env python3
"""Finds import cycles between the modules of each crate in `crates/`.

docs/ARCHITECTURE.md §1 asks for none: within a crate, if module `a` uses module `b`,
`b` must not use `a`, directly or through others. A module is a source file
(`src/a/b.rs` or `src/a/b/mod.rs` is `a::b`); its uses are the `crate::`, `super::` and
`self::` paths in its non-test code, each resolved to the deepest module it names, and
names re-exported by a module (`pub use x::Y;`) resolved to the module they come from.
Edges between a module and its own ancestors or descendants are not counted: a parent
declares and re-exports its children, and a child may use its parent's items.

Prints each cycle (a strongly connected component of two or more modules) and exits 1
if there is one, 0 if there is none.
"""

import re
import sys
from pathlib import Path

PATH = re.compile(r"\b(crate|super|self)((?:::[A-Za-z_][A-Za-z0-9_]*)+)")
USE_BLOCK = re.compile(r"\buse\s+([^;]+);", re.S)
PUB_USE = re.compile(r"\bpub(?:\([^)]*\))?\s+use\s+([^;]+);", re.S)


def module_of(src: Path, file: Path) -> tuple:
    """The module path of a source file, as a tuple of names (() for the root)."""
    parts = list(file.relative_to(src).with_suffix("").parts)
    if parts[-1] in ("lib", "main", "mod"):
        parts.pop()
    return tuple(parts)


def strip_tests(text: str) -> str:
    """The text up to its first `#[cfg(test)]` item (tests may use anything)."""
    text = re.sub(r"//[^\n]*", "", text)
    cut = text.find("#[cfg(test)]")
    return text if cut < 0 else text[:cut]


def expand(tree: str) -> list:
    """`a::{b, c::{d, e}}` as the paths `a::b`, `a::c::d`, `a::c::e`."""
    tree = re.sub(r"\s+", "", tree)
    out = []

    def walk(prefix: str, rest: str):
        brace = rest.find("{")
        if brace < 0:
            for item in split_top(rest):
                out.append(prefix + item.split(" as ")[0])
            return
        head, body = rest[:brace], rest[brace + 1 : rest.rfind("}")]
        for item in split_top(body):
            walk(prefix + head, item)

    walk("", tree)
    return out


def split_top(s: str) -> list:
    """Splits on the commas not inside braces."""
    items, depth, cur = [], 0, ""
    for ch in s:
        if ch == "{":
            depth += 1
        elif ch == "}":
            depth -= 1
        if ch == "," and depth == 0:
            items.append(cur)
            cur = ""
        else:
            cur += ch
    if cur:
        items.append(cur)
    return [i for i in items if i]


def absolute(module: tuple, path: str) -> tuple:
    """The names of a `crate::`/`super::`/`self::` path, from the crate's root."""
    names = path.split("::")
    base = list(module)
    if names[0] == "crate":
        base, names = [], names[1:]
    while names and names[0] in ("super", "self"):
        if names[0] == "super":
            base = base[:-1]
        names = names[1:]
    return tuple(base + names)


def crate_cycles(src: Path) -> list:
    files = sorted(src.rglob("*.rs"))
    modules = {module_of(src, f): strip_tests(f.read_text()) for f in files}
    # Re-exported names: (module, name) -> the names' full path.
    exports = {}
    for module, text in modules.items():
        for tree in PUB_USE.findall(text):
            for path in expand(tree):
                if path.split("::")[0] in ("crate", "super", "self"):
                    full = absolute(module, path)
                    exports[module + (full[-1],)] = full

    def resolve(names: tuple) -> tuple:
        for _ in range(8):
            if names in exports and exports[names] != names:
                names = exports[names]
            else:
                break
        while names and names not in modules:
            names = names[:-1]
        return names

    edges, why = {}, {}
    for module, text in modules.items():
        paths = [p for tree in USE_BLOCK.findall(text) for p in expand(tree)]
        paths += [m.group(1) + m.group(2) for m in PATH.finditer(text)]
        for path in paths:
            if path.split("::")[0] not in ("crate", "super", "self"):
                continue
            target = resolve(absolute(module, path))
            # Between the two subtrees under their lowest common ancestor.
            common = 0
            while common < min(len(module), len(target)) and module[common] == target[common]:
                common += 1
            if common < len(module) and common < len(target):
                a, b = module[: common + 1], target[: common + 1]
                edges.setdefault(a, set()).add(b)
                edges.setdefault(b, set())
                why.setdefault((a, b), (module, target))
    return [(comp, [why[(a, b)] for a in comp for b in comp if (a, b) in why])
            for comp in strongly_connected(edges)]


def strongly_connected(edges: dict) -> list:
    """Tarjan's algorithm: the components of two or more nodes."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
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
            if len(comp) > 1:
                out.append(sorted(comp))

    sys.setrecursionlimit(10000)
    for v in edges:
        if v not in index:
            visit(v)
    return out


def main() -> int:
    root = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("crates")
    found = 0
    for src in sorted(root.glob("*/src")):
        for comp, uses in crate_cycles(src):
            found += 1
            names = ", ".join("::".join(m) for m in comp)
            print(f"{src.parent.name}: modules that use each other: {names}")
            for user, used in uses:
                print(f"    {'::'.join(user)} uses {'::'.join(used) or '(root)'}")
    if found == 0:
        print("module-cycles: no import cycles between modules")
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
