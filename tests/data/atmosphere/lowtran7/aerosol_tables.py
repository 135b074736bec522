"""Extract LOWTRAN 7's aerosol tables from lowtran7.f, unchanged, into the two CSV files
the built-in model embeds (src/atmosphere/data/lowtran7_aerosol_spectra.csv and
lowtran7_aerosol_profiles.csv).

Usage: python3 aerosol_tables.py PATH/TO/lowtran7.f OUT_DIR

Spectra (BLOCK DATA EXTDTA): the 47 wavelengths VX2 (um) and, normalised to 1 at 0.55 um,
the extinction (E) and absorption (A) coefficients of the rural (RUR), urban (URB),
maritime (OCN) and tropospheric (TRO) models at relative humidity 0, 70, 80 and 99 %
(suffix 1-4), of the background stratospheric (BST) and of the meteoric-dust (DME) models;
then the asymmetry parameters g (not normalised) of the same models (RURG1-4, ..., BSTSYM,
DMESYM; "modified to include asymmetry data - Jan 1986 (A.E.R. Inc.)" in lowtran7.f).
Profiles (BLOCK DATA PRFDTA): the altitudes ZHT (km) and the 0.55 um extinction (km-1) of
the boundary layer at visibilities 50, 23, 10, 5 and 2 km (HZ2K), of the troposphere
(fall-winter and spring-summer at 50 and 23 km), of the background stratosphere
(fall-winter, spring-summer) and of the upper atmosphere (UPNATM)."""
import re
import sys


def statements(src):
    """DATA statements as (names, values text), continuation lines joined."""
    lines = src.split("\n")
    out, cur = [], None
    for l in lines:
        if l[:1] in ("C", "c", "*", "!"):
            continue
        if len(l) > 5 and l[5] not in (" ", "0") and l[:5].strip() == "" and cur is not None:
            cur += " " + l[6:72]
            continue
        if cur is not None:
            out.append(cur)
            cur = None
        if re.match(r"^\s+DATA\s", l[:72]):
            cur = l[:72]
    if cur is not None:
        out.append(cur)
    return out


def values(text):
    vals = []
    for tok in text.replace("\n", " ").split(","):
        tok = tok.strip()
        if not tok:
            continue
        if "*" in tok:
            n, v = tok.split("*")
            vals += [float(v)] * int(n)
        else:
            vals.append(float(tok.replace("D", "E")))
    return vals


def arrays(src, names):
    got = {}
    for s in statements(src):
        m = re.match(r"\s*DATA\s+(.*?)\s*/(.*)/\s*$", s, re.S)
        if not m:
            continue
        name = m.group(1).strip()
        if name in names:
            got[name] = values(m.group(2))
    missing = [n for n in names if n not in got]
    if missing:
        sys.exit(f"not found in the source: {missing}")
    return got


def main():
    src = open(sys.argv[1]).read()
    out = sys.argv[2]
    spec = ["VX2"]
    for m in ("RUR", "URB", "OCN", "TRO"):
        spec += [f"{m}E{i}" for i in range(1, 5)] + [f"{m}A{i}" for i in range(1, 5)]
    spec += ["BSTEXT", "BSTABS", "DMEEXT", "DMEABS"]
    for m in ("RUR", "URB", "OCN", "TRO"):
        spec += [f"{m}G{i}" for i in range(1, 5)]
    spec += ["BSTSYM", "DMESYM"]
    a = arrays(src, spec)
    assert all(len(a[n]) == 47 for n in spec), {n: len(a[n]) for n in spec}
    with open(f"{out}/lowtran7_aerosol_spectra.csv", "w") as f:
        f.write("# LOWTRAN 7 aerosol extinction and absorption coefficients normalised to 1 at 0.55 um, and asymmetry\n")
        f.write("# parameters g (columns *G*, *SYM; not normalised), copied\n")
        f.write("# unchanged from BLOCK DATA EXTDTA of lowtran7.f (rev. 4.2; tests/data/atmosphere/lowtran7/aerosol_tables.py)\n")
        f.write(",".join(spec) + "\n")
        for i in range(47):
            f.write(",".join(repr(a[n][i]) for n in spec) + "\n")
    # HZ2K is set element by element: DATA HZ2K(1,1),...,HZ2K(1,5)/.../
    hz = {}
    for s in statements(src):
        m = re.match(r"\s*DATA\s+HZ2K\((\d+),1\).*?/(.*)/\s*$", s, re.S)
        if m:
            hz[int(m.group(1))] = values(m.group(2))
    assert sorted(hz) == [1, 2, 3] and all(len(v) == 5 for v in hz.values()), hz
    prof = ["ZHT", "FAWI50", "FAWI23", "SPSU50", "SPSU23", "BASTFW", "BASTSS", "UPNATM"]
    p = arrays(src, prof)
    assert all(len(p[n]) == 34 for n in prof), {n: len(p[n]) for n in prof}
    cols = ["ZHT"] + [f"HZ2K_{v}" for v in (50, 23, 10, 5, 2)] + prof[1:]
    with open(f"{out}/lowtran7_aerosol_profiles.csv", "w") as f:
        f.write("# LOWTRAN 7 aerosol 0.55 um extinction profiles, km-1, at altitudes ZHT (km), copied unchanged from\n")
        f.write("# BLOCK DATA PRFDTA of lowtran7.f (rev. 4.2; HZ2K_V: boundary layer at visibility V km, given at 0-2 km)\n")
        f.write(",".join(cols) + "\n")
        for i in range(33):  # the 34th altitude is the 99999 km sentinel
            row = [p["ZHT"][i]] + [hz[i + 1][j] if i < 3 else 0.0 for j in range(5)] + [p[n][i] for n in prof[1:]]
            f.write(",".join(repr(v) for v in row) + "\n")


if __name__ == "__main__":
    main()
