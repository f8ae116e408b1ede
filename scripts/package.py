"""Builds the installable packages of the add-on, each carrying the native module:

    python3 scripts/package.py OUT_DIR

  hairdyn-<version>.zip            an add-on zip (a hairdyn/ folder) for Preferences > Add-ons >
                                   Install, Blender 3.4 and later
  hairdyn-<version>-extension.zip  an extension package (blender_manifest.toml at its root)
                                   for Preferences > Get Extensions > Install from Disk, 4.2+

Both carry every native module the build made, one per CPython (_native.cpython-311-*.so for
Blender 3.4-5.0, _native.cpython-313-*.so for Blender 5.1+).
"""
import re
import sys
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "addon" / "hairdyn"


def native_modules():
    """The built native modules, one per CPython: {"cpython-311": path, ...}."""
    found = {}
    for path in sorted(PACKAGE.glob("_native*.so")):
        tag = re.search(r"\.(cpython-\d+)", path.name)
        found[tag.group(1) if tag else path.name] = path
    return found


def package_files():
    """Everything the add-on needs at run time: sources, presets, manifest, native modules."""
    if not native_modules():
        raise SystemExit(f"package: no native module in {PACKAGE}: run 'make build' first")
    files = sorted(p for p in PACKAGE.rglob("*") if p.is_file() and "__pycache__" not in p.parts
                   and p.suffix in (".py", ".toml", ".so"))
    return files


def version():
    text = (PACKAGE / "blender_manifest.toml").read_text()
    return re.search(r'^version = "([^"]+)"', text, re.M).group(1)


def build(out_dir):
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    files = package_files()
    addon_zip = out_dir / f"hairdyn-{version()}.zip"
    extension_zip = out_dir / f"hairdyn-{version()}-extension.zip"
    with zipfile.ZipFile(addon_zip, "w", zipfile.ZIP_DEFLATED) as archive:
        for path in files:
            archive.write(path, Path("hairdyn") / path.relative_to(PACKAGE))
    with zipfile.ZipFile(extension_zip, "w", zipfile.ZIP_DEFLATED) as archive:
        for path in files:
            archive.write(path, path.relative_to(PACKAGE))
    return addon_zip, extension_zip


if __name__ == "__main__":
    print(f"package: native modules for {', '.join(native_modules())}")
    for built in build(sys.argv[1] if len(sys.argv) > 1 else ROOT / "out" / "dist"):
        print(f"package: {built}")
