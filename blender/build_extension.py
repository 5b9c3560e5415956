"""Write the Blender extension zip: blender/sorpia_blender with the sorpia wheel.

    python blender/build_extension.py WHEEL OUTDIR [DEPENDENCY_WHEEL ...]

writes OUTDIR/sorpia_blender-VERSION.zip, VERSION the sorpia wheel's: the
add-on's files at the zip's root, the wheels under wheels/ (sorpia's, and
any dependency Blender lacks: none today, sorpia needs numpy alone and
Blender ships it), and blender_manifest.toml with the version, the wheels'
paths under ``wheels`` and the platforms every wheel has under ``platforms``
(Blender installs an extension only on the platforms listed, and unpacks its
wheels itself, without resolving dependencies). Prints the zip's path.
"""

from __future__ import annotations

import re
import sys
import zipfile
from pathlib import Path

SOURCE = Path(__file__).resolve().parent / "sorpia_blender"
# Wheel platform tags (PEP 425, the architecture at the end) as Blender's platform names.
PLATFORMS = (
    (r"^(many|musl)?linux.*_x86_64$", "linux-x64"),
    (r"^(many|musl)?linux.*_aarch64$", "linux-arm64"),
    (r"^macosx_.*_(arm64)$", "macos-arm64"),
    (r"^macosx_.*_(x86_64)$", "macos-x64"),
    (r"^win_amd64$", "windows-x64"),
    (r"^win_arm64$", "windows-arm64"),
)


def wheel_tags(wheel: Path) -> tuple[str, list[str]]:
    """The wheel's version and its Blender platforms, from its file name
    (name-version-python-abi-platform.whl; the platform part may hold several
    tags joined by dots)."""
    parts = wheel.name[:-len(".whl")].split("-")
    if not wheel.name.endswith(".whl") or len(parts) < 5:
        raise SystemExit(f"{wheel}: not a wheel's file name (name-version-python-abi-platform.whl)")
    platforms = []
    for tag in parts[-1].split("."):
        found = [name for pattern, name in PLATFORMS if re.match(pattern, tag)]
        if not found:
            raise SystemExit(f"{wheel}: platform tag {tag!r} is none Blender installs on")
        platforms += [p for p in found if p not in platforms]
    return parts[1], platforms


def manifest(version: str, wheel_names: list[str], platforms: list[str]) -> str:
    text = (SOURCE / "blender_manifest.toml").read_text()
    text, n = re.subn(r'(?m)^version = ".*"$', f'version = "{version}"', text)
    if n != 1:
        raise SystemExit("blender_manifest.toml: no version line to set")
    wheels = [f"./wheels/{name}" for name in wheel_names]
    return text + f"platforms = {platforms!r}\nwheels = {wheels!r}\n".replace("'", '"')


def build(wheel: Path, outdir: Path, dependencies: tuple = ()) -> Path:
    version, platforms = wheel_tags(wheel)
    for dependency in dependencies:  # the platforms every wheel runs on
        platforms = [p for p in platforms if p in wheel_tags(dependency)[1]]
    if not platforms:
        raise SystemExit(f"{wheel} and {', '.join(map(str, dependencies))} share no platform")
    outdir.mkdir(parents=True, exist_ok=True)
    out = outdir / f"sorpia_blender-{version}.zip"
    partial = out.with_suffix(".zip.partial")
    wheels = [wheel, *dependencies]
    with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("blender_manifest.toml", manifest(version, [w.name for w in wheels], platforms))
        for path in sorted(SOURCE.rglob("*.py")):
            if "__pycache__" not in path.parts:
                z.write(path, path.relative_to(SOURCE).as_posix())
        for w in wheels:
            z.write(w, f"wheels/{w.name}", compress_type=zipfile.ZIP_STORED)  # a wheel is a zip already
    partial.replace(out)
    return out


if __name__ == "__main__":
    if len(sys.argv) < 3:
        raise SystemExit(__doc__)
    print(build(Path(sys.argv[1]), Path(sys.argv[2]), tuple(Path(p) for p in sys.argv[3:])))
