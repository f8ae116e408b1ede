"""The add-on zip (3.4+) and the extension package (4.2+) install into a clean user folder and
enable, carrying the native module of every CPython built (3.11, and 3.13 where the machine has
one) and loading the one that matches the host."""
import importlib.util
import json
import os
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import bpy

from conftest import ROOT, host_name


def package_module():
    spec = importlib.util.spec_from_file_location("hairdyn_package", ROOT / "scripts" / "package.py")
    package = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(package)
    return package


def build_packages(out_dir):
    return package_module().build(out_dir)


def test_packages_carry_every_native_module(tmp_path):
    """Both packages hold one module per CPython built; the build made the 3.13 one wherever
    setup.sh found a Python 3.13 (its venv, .venv313, exists)."""
    natives = package_module().native_modules()
    expected = {"cpython-311"} | ({"cpython-313"} if (ROOT / ".venv313").is_dir() else set())
    assert expected <= set(natives), natives
    here = f"cpython-{sys.version_info.major}{sys.version_info.minor}"
    assert natives[here].name == "_native" + sysconfig.get_config_var("EXT_SUFFIX")
    for built, prefix in zip(build_packages(tmp_path), ("hairdyn/", "")):
        with zipfile.ZipFile(built) as archive:
            names = set(archive.namelist())
        assert {prefix + path.name for path in natives.values()} <= names, (built, names)


def test_package_installs_into_a_clean_user_folder(tmp_path):
    addon_zip, extension_zip = build_packages(tmp_path / "dist")
    out = tmp_path / "install.json"
    env = dict(os.environ)
    check = str(ROOT / "python_tests" / "install_check.py")
    if host_name() == "blender":
        env.update(BLENDER_USER_CONFIG=str(tmp_path / "user" / "config"),
                   BLENDER_USER_SCRIPTS=str(tmp_path / "user" / "scripts"))
        command = [bpy.app.binary_path, "-b", "--factory-startup", "--python", check, "--",
                   str(addon_zip), "addon", str(out)]
        installed_under = tmp_path / "user" / "scripts" / "addons" / "hairdyn"
    else:
        env.update(BLENDER_USER_RESOURCES=str(tmp_path / "user"))
        command = [sys.executable, check, str(extension_zip), "extension", str(out)]
        installed_under = tmp_path / "user" / "extensions" / "user_default" / "hairdyn"
    process = subprocess.run(command, env=env, capture_output=True, text=True, timeout=300)
    assert out.is_file(), process.stdout[-2000:] + process.stderr[-2000:]
    result = json.loads(out.read_text())
    assert all(step == ["FINISHED"] for step in result["steps"]), result
    assert result["registered"]
    assert result["native"][0], result["native"]
    assert result["file"].startswith(str(installed_under))
    # the installed copy of the module built for this host's Python
    assert result["native_file"] == str(Path(result["file"]).parent / (
        "_native" + sysconfig.get_config_var("EXT_SUFFIX")))
