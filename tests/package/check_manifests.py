#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The PlatformIO and Arduino manifests agree with the build: the version is
the CMake project's, library.json's srcFilter picks exactly the sources of
fdsurf_core and fdsurf_hal and its -I directories exist, library.properties
has the fields the Arduino library specification (1.5, rev 2.2) requires.
Usage: check_manifests.py SOURCE_DIR VERSION"""
import fnmatch
import json
import pathlib
import re
import sys

src = pathlib.Path(sys.argv[1])
version = sys.argv[2]
errors = []


def cmake_sources(cmake_file, target):
    text = (src / cmake_file).read_text()
    block = re.search(r"add_library\(" + target + r" STATIC(.*?)\)", text, re.S).group(1)
    base = pathlib.Path(cmake_file).parent
    return {str(base / s) for s in block.split()}


core = cmake_sources("firmware/CMakeLists.txt", "fdsurf_core") | cmake_sources(
    "hal/CMakeLists.txt", "fdsurf_hal")

pio = json.loads((src / "library.json").read_text())
if pio["version"] != version:
    errors.append(f"library.json version {pio['version']}, project {version}")
every = [str(p.relative_to(src)) for p in src.rglob("*") if p.is_file()
         and not any(part.startswith(("build", ".")) for part in p.relative_to(src).parts)]
picked = set()
for f in every:
    keep = False
    for rule in pio["build"]["srcFilter"]:
        sign, pattern = rule[0], rule[2:-1]
        if pattern == "*" or fnmatch.fnmatch(f, pattern):
            keep = sign == "+"
    if keep:
        picked.add(f)
if picked != core:
    errors.append(f"srcFilter picks {sorted(picked ^ core)} differently from CMake")
for flag in pio["build"]["flags"]:
    if flag.startswith("-I") and not (src / flag[2:].strip()).is_dir():
        errors.append(f"library.json: {flag}: no such directory")
if not (src / pio["build"]["includeDir"]).is_dir():
    errors.append("library.json: includeDir does not exist")

props = dict(line.split("=", 1) for line in (src / "library.properties").read_text().splitlines()
             if "=" in line and not line.startswith("#"))
for field in ("name", "version", "author", "maintainer", "sentence", "paragraph", "category",
              "url", "architectures"):
    if not props.get(field):
        errors.append(f"library.properties: no {field}")
if props.get("version") != version:
    errors.append(f"library.properties version {props.get('version')}, project {version}")
if props.get("category") not in ("Display", "Communication", "Signal Input/Output", "Sensors",
                                 "Device Control", "Timing", "Data Storage", "Data Processing",
                                 "Other"):
    errors.append("library.properties: category is not one of the specification's")

for e in errors:
    print(e, file=sys.stderr)
if errors:
    sys.exit(1)
print(f"manifests: version {version}, {len(core)} core sources")
