"""Generates the fuzz corpus of configs in tests/data/fuzz/config/ (tests/fuzz.rs runs it).

Each corpus file is a shipped config (configs/) with one mutation: a numeric value scaled by a
power of ten (the unit slips of issue 18: 1e-30 kg/m^3, 1e308 Pa), set to zero, negated, or a
line dropped or duplicated. The draws are seeded, so a rerun rewrites the same files:

    python3 tests/data/fuzz/mutate.py
"""

import pathlib
import random
import re

ROOT = pathlib.Path(__file__).resolve().parents[3]
OUT = pathlib.Path(__file__).resolve().parent / "config"
COUNT = 40
NUMBER = re.compile(r"^(\s*[a-z_]+\s*=\s*)(-?[0-9][0-9.eE+-]*)\s*(#.*)?$")


def mutate(lines, rng):
    numeric = [i for i, line in enumerate(lines) if NUMBER.match(line)]
    kind = rng.choice(["scale", "scale", "scale", "zero", "negate", "drop", "duplicate"])
    i = rng.choice(numeric)
    head, value, _ = NUMBER.match(lines[i]).groups()
    if kind == "scale":
        power = rng.choice([-300, -30, -10, -3, 3, 10, 30, 300])
        new = f"{float(value) * 10.0 ** power:e}" if "." in value or "e" in value.lower() else None
        if new is None:
            # Integers (mesh cells, orders) grow or shrink by a factor instead.
            new = str(int(value) * rng.choice([0, 3, 1000, 10**9]))
        lines[i] = head + new
        return f"{head.strip()} {value} -> {new}"
    if kind == "zero":
        lines[i] = head + "0"
        return f"{head.strip()} {value} -> 0"
    if kind == "negate":
        lines[i] = head + "-" + value.lstrip("-")
        return f"{head.strip()} {value} -> -{value.lstrip('-')}"
    if kind == "drop":
        line = lines.pop(i)
        return f"dropped `{line.strip()}`"
    lines.insert(i, lines[i])
    return f"duplicated `{lines[i].strip()}`"


def main():
    rng = random.Random(18)
    shipped = sorted((ROOT / "configs").glob("*.toml"))
    OUT.mkdir(exist_ok=True)
    for old in OUT.glob("*.toml"):
        old.unlink()
    for k in range(COUNT):
        source = rng.choice(shipped)
        lines = [
            line.replace("../tests/data/", "../../")
            for line in source.read_text().splitlines()
            if not line.lstrip().startswith("#")
        ]
        what = mutate(lines, rng)
        text = f"# {source.name}: {what}\n" + "\n".join(lines) + "\n"
        (OUT / f"{k:03}.toml").write_text(text)


if __name__ == "__main__":
    main()
