#!/usr/bin/env python3
"""Gathers the figures the test suite measured (target/measurements/*.json, written by the
tests' `common::record`) into docs/measurements.json, prints the README's results table from
docs/results.md.in with them, and lists them in docs/measurements.md.

    rm -rf target/measurements                         # no figures of an older run
    ANTIRADIANCE_RECORD_FIGURES=1 cargo test --release   # measure (no check against the file)
    python3 scripts/measurements.py                      # gather, then commit the three files

tests/readme.rs fails when the README's table is not docs/results.md.in printed from
docs/measurements.json, or quotes a figure the file lacks; `record` fails when a test measures
a figure away from the file's value. Figures not measured this run keep their value and the
commit that measured them (`--fresh` drops them instead)."""
import json, os, pathlib, re, subprocess, sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
BEGIN = "<!-- results: printed by scripts/measurements.py from docs/results.md.in -->"
END = "<!-- end of results -->"
LIST_BEGIN = "<!-- figures: written by scripts/measurements.py -->"
LIST_END = "<!-- end of figures -->"
SUPER = str.maketrans("0123456789-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻")


def fmt(value, spec):
    """The tiny format language of docs/results.md.in (tests/readme.rs has the same)."""
    kind, digits = re.fullmatch(r"([a-z]+)(\d*)", spec).groups()
    n = int(digits) if digits else 0
    minus = "−" if value < 0 else ""
    if kind == "f":
        return f"{value:.{n}f}"
    if kind == "p":
        return f"{abs(value) * 100:.{n}f}%"
    if kind == "sp":
        return ("+" if value >= 0 else "−") + f"{abs(value) * 100:.{n}f}%"
    if kind == "i":
        return f"{round(value):,}"
    if kind == "x":
        return f"{value:.{n}f}×"
    if kind == "e":
        m, e = f"{abs(value):.{n}e}".split("e")
        return f"{minus}{m}·10{str(int(e)).translate(SUPER)}"
    raise SystemExit(f"unknown format {spec}")


def render(template, figures):
    def one(m):
        key, spec = m.group(1), m.group(2)
        if key not in figures:
            raise SystemExit(f"docs/results.md.in quotes {key}, which the tests did not measure")
        return fmt(figures[key]["value"], spec)
    return re.sub(r"\{([a-z0-9.\-]+):([a-z]+\d*)\}", one, template)


def replace_between(text, begin, end, body):
    a, b = text.index(begin) + len(begin), text.index(end)
    return text[:a] + "\n" + body.rstrip("\n") + "\n" + text[b:]


def main():
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    if not target.is_absolute():
        target = ROOT / target
    found = sorted((target / "measurements").glob("*.json"))
    if not found:
        sys.exit(f"no figures in {target / 'measurements'}: run the suite first")
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                            capture_output=True, text=True).stdout.strip()
    old_path = ROOT / "docs/measurements.json"
    figures = {}
    if "--fresh" not in sys.argv and old_path.exists():
        old = json.loads(old_path.read_text())
        for k, v in old["figures"].items():
            figures[k] = {**v, "commit": v.get("commit", old["commit"])}
    for f in found:
        d = json.loads(f.read_text())
        figures[d["key"]] = {"value": d["value"], "test": d["test"], "commit": commit}
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
    machine = f"{cpu}, {os.cpu_count()} cores, lavapipe"
    out = {"commit": commit, "machine": machine, "figures": dict(sorted(figures.items()))}
    (ROOT / "docs/measurements.json").write_text(json.dumps(out, indent=1, ensure_ascii=False) + "\n")
    readme = (ROOT / "README.md").read_text()
    table = render((ROOT / "docs/results.md.in").read_text(), figures)
    (ROOT / "README.md").write_text(replace_between(readme, BEGIN, END, table))
    rows = [f"Measured by the test suite on {machine}, each at the commit beside it "
            "(`ANTIRADIANCE_RECORD_FIGURES=1 cargo test --release`, then `python3 scripts/measurements.py`); "
            "each test holds its figure to this file.", "", "| figure | value | test binary | commit |", "|---|---|---|---|"]
    rows += [f"| `{k}` | {v['value']:.6g} | `{v['test']}` | {v['commit']} |" for k, v in sorted(figures.items())]
    md = (ROOT / "docs/measurements.md").read_text()
    (ROOT / "docs/measurements.md").write_text(replace_between(md, LIST_BEGIN, LIST_END, "\n".join(rows)))
    print(f"{len(figures)} figures from {commit} on {machine}")


if __name__ == "__main__":
    main()
