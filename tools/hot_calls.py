#!/usr/bin/env python3
"""Checks that the hot kernels of a release binary make no out-of-line calls to helpers that
are meant to vanish into them.

Why: a closure of `array::map` / `Lanes::from_fn`, a glam operator or an intrinsic called
from a function that is not compiled for its target feature can stay an out-of-line call when
an unrelated change moves an inlining decision. In DIRT's four-wide triangle test this cost
1.5-1.7x the CPU time per ray with no change to the tracer's source (docs/notes/dirt.md, the
`try_map` entry). Callgrind sees the extra instructions, wall-time pairs see the cost, but
neither says why; the disassembly does.

How: `objdump -d -C` of the binary, the call instructions of every function whose demangled
name matches one of HOT, and the callees among them that match one of FORBIDDEN. Prints a
table per function and exits 1 if any forbidden call is found, else 0.

A hot kernel must not call a closure written outside it: a closure is compiled with the
target features of the function it is written in, so one defined in a shared generic helper
and called from an AVX2 / AVX-512 entry point runs as baseline code, out of line. The beam
caster's watertight AVX2 tier ran its whole packet kernel that way (docs/notes/vr.md,
2026-12-06). Exceptions: ALLOWED_CLOSURES.

Calls through the GOT (how the binary reaches `floorf` and the other rounding functions of
the x86-64 baseline) are resolved to their symbols; the LDC tracer's DDA called `floorf`
four times per block until it took `parallax_core::math::floor_i64` (docs/notes/ldc.md,
2026-12-06).

Also a software bit count in a hot kernel: `count_ones` compiled without the `popcnt` target
feature becomes a shift-and-mask sequence with the constant 0x33333333 (the AVX-512 entry
points of the beam caster and the BVH packets were compiled that way until their feature
lists named POPCNT: docs/notes/vr.md, 2026-12-06). Counted like a forbidden call.

Usage (after `cargo build --release [--features embree] --bin parallax`):

    python3 tools/hot_calls.py [target/release/parallax] [--all]

Anywhere in the project (hot or not): an out-of-line call to a `core::core_arch` vector
intrinsic means a function that uses SIMD lanes without being compiled for their target
feature (a generic or `#[inline(never)]` helper called from a kernel): each such call moves
one vector operation through memory. The beam caster's `ill_conditioned` made 110 of them
until it was inlined into its callers (docs/notes/vr.md, 2026-12-06). Such calls fail the
check too.

`--all` lists forbidden calls from every `parallax_*` function, hot or not (for a look
around; cold paths such as constructors may call them).
"""
import re
import subprocess
import sys

# The kernels the benches time, in the copies this project runs on x86-64 with AVX2 / AVX-512
# (the portable copies run only where those are missing).
HOT = [
    r"parallax_screen::dirt::tri4::Query::test_v[34]\b",
    r"parallax_screen::dirt::walk::walk_dir_v[34]\b",
    r"parallax_screen::dirt::DirtTracer::trace_v[34]\b",
    r"parallax_screen::dirt::DirtTracer::(closest_hit|occluded)_counted\b",
    r"parallax_bvh::traverse8::.*::(closest8|any8)_avx2",
    r"parallax_bvh::packet_lanes::.*::packets_avx(2|512)\b",
    r"parallax_bvh::packet::.*::packet16_avx2\b",
    r"parallax_vr::cast::setup::run_setup_avx(2|2_16|512)\b",
    r"parallax_vr::cast::setup::bands::refine_run\b",
    r"parallax_vr::cast::packet_kernel::run_packets_avx2\b",
    r"parallax_screen::quadtree::merge_rows(8|16)::.*::parent_row(8|16)\b",
    r"parallax_screen::quadtree::.*row_avx(2|512)\b",
    r"parallax_screen::quadtree::trigger_avx512::pixel_triggers_row16\b",
    r"parallax_screen::quadtree::eff_planes_avx512::.*::row16\b",
    r"parallax_raster::dirt::(build::chunk_frags_v4|fill::fill_band_v4)\b",
    r"parallax_screen::ldc::traverse::.*::trace\b",
]

# Closures a hot kernel may call out of line (module docs): (caller pattern, callee pattern,
# why). A closure defined inside the kernel itself is always allowed (it has the kernel's
# target features; such calls are once per band or chunk).
ALLOWED_CLOSURES = [
    (
        r"parallax_vr::cast::packet_kernel::run_packets_avx2",
        r"parallax_vr::cast::intersect::test_tile::\{\{closure\}\}",
        "the fallback of a declined packet: one ray through `closest_one`, rare",
    ),
]

# Intrinsics that must never be called out of line from the project's code (module docs).
NEVER_OUT_OF_LINE = re.compile(r"core::core_arch::x86(_64)?::(avx|sse|f16c|fma)")

# Helpers that must be inlined where they are used in a kernel.
FORBIDDEN = [
    r"try_map",
    r"core::array::.*::map\b",
    r"::from_fn::\{\{closure\}\}",
    r"core::core_arch::",
    r"^<glam::",
    # `f32::floor` and friends: a library call on the x86-64 baseline (no SSE4.1 `roundss`);
    # `parallax_core::math::floor_i32` / `floor_i64` are the inline forms.
    r"^(floor|ceil|round|trunc)f?$",
]

FUNC = re.compile(r"^[0-9a-f]+ <(.*)>:$")
CALL = re.compile(r"\bcall\s+[0-9a-f]*\s*<(.*)>")
# A call through the global offset table (`call *0x..(%rip)  # <slot>`): the callee is the
# symbol the slot's relocation points at (`got_targets`).
GOT_CALL = re.compile(r"\bcall\s+\*0x[0-9a-f]+\(%rip\)\s+#\s*([0-9a-f]+)")
# The 2-bit step's mask of a software population count (`0x33333333` or its 64-bit form).
SOFT_POPCOUNT = re.compile(r"\$0x3333333333333333\b|\$0x33333333\b")
SOFT_POPCOUNT_NAME = "software bit count (no POPCNT)"


def got_targets(binary):
    """The symbol each GOT slot of the binary points at (`objdump -R` relative relocations,
    resolved with `nm`)."""
    names = {}
    for line in subprocess.run(
        ["nm", "-C", binary], check=True, capture_output=True, text=True
    ).stdout.splitlines():
        parts = line.split(maxsplit=2)
        if len(parts) == 3:
            names.setdefault(int(parts[0], 16), parts[2])
    slots = {}
    for line in subprocess.run(
        ["objdump", "-R", binary], check=True, capture_output=True, text=True
    ).stdout.splitlines():
        m = re.match(r"^([0-9a-f]+) R_X86_64_RELATIVE\s+\*ABS\*\+0x([0-9a-f]+)$", line)
        if m and int(m.group(2), 16) in names:
            slots[int(m.group(1), 16)] = names[int(m.group(2), 16)]
    return slots


def calls(binary):
    """Yields (function, callee) for every direct call in the binary's text, and for every
    call through the GOT whose slot resolves to a symbol."""
    slots = got_targets(binary)
    out = subprocess.run(
        ["objdump", "-d", "-C", "--no-show-raw-insn", binary],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    func = None
    for line in out.splitlines():
        m = FUNC.match(line)
        if m:
            func = m.group(1)
            continue
        if func is None:
            continue
        m = CALL.search(line)
        if m:
            yield func, m.group(1)
            continue
        m = GOT_CALL.search(line)
        if m and int(m.group(1), 16) in slots:
            yield func, slots[int(m.group(1), 16)]
        elif SOFT_POPCOUNT.search(line):
            yield func, SOFT_POPCOUNT_NAME


def foreign_closure_allowed(func, callee):
    """Whether hot `func` may call closure `callee` out of line: one of its own closures (the
    callee's path starts with the kernel's), or an entry of ALLOWED_CLOSURES."""
    own = re.sub(r"::\{\{closure\}\}.*$", "", callee)
    base = re.sub(r"::\{\{closure\}\}.*$", "", func)
    if own == base or own.startswith(base + "::"):
        return True
    return any(re.search(f, func) and re.search(c, callee) for f, c, _ in ALLOWED_CLOSURES)


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    everything = "--all" in sys.argv[1:]
    binary = args[0] if args else "target/release/parallax"
    hot = [re.compile(p) for p in HOT]
    bad = [re.compile(p) for p in FORBIDDEN]
    counts, seen_hot, everywhere = {}, set(), 0
    for func, callee in calls(binary):
        is_hot = any(p.search(func) for p in hot)
        if is_hot:
            seen_hot.add(func)
        if "parallax_" in func and NEVER_OUT_OF_LINE.search(callee):
            key = (func, callee)
            counts[key] = counts.get(key, 0) + 1
            everywhere += 1
            continue
        if not (is_hot or (everything and "parallax_" in func)):
            continue
        if is_hot and "{{closure}}" in callee and not foreign_closure_allowed(func, callee):
            key = (func, callee)
            counts[key] = counts.get(key, 0) + 1
            continue
        if callee == SOFT_POPCOUNT_NAME or any(p.search(callee) for p in bad):
            key = (func, callee)
            counts[key] = counts.get(key, 0) + 1
    print(f"{binary}: {len(seen_hot)} hot functions found (of {len(HOT)} patterns)")
    if not seen_hot:
        print("no hot function found: not a parallax release binary, or the names moved")
        return 1
    if not counts:
        print("no forbidden out-of-line calls")
        return 0
    print("| calls | function | callee |\n|---|---|---|")
    for (func, callee), n in sorted(counts.items(), key=lambda kv: -kv[1]):
        print(f"| {n} | `{func}` | `{callee}` |")
    hot_hits = sum(n for (f, _), n in counts.items() if any(p.search(f) for p in hot))
    return 1 if hot_hits or everywhere else 0


if __name__ == "__main__":
    sys.exit(main())
