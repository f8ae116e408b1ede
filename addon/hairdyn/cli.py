"""hairdyn's headless entry point.

In Blender:        blender -b scene.blend --python addon/hairdyn/cli.py -- run --object Hair
                       --frames 1 48 --set method=follow --report out.json
With the bpy module: python addon/hairdyn/cli.py --blend scene.blend run --object Hair ...

`run` simulates into the output objects; `bake` also writes every frame to the cache
(--cache FOLDER, --resume to continue a bake that stopped). Nothing draws headless, so the
output objects get only the last frame (Runner's show_frames); `wedge` bakes a table of parameter
sets in parallel on Dask (wedge.py); `export` writes a bake to Alembic or USD (export.py).

`--set name=value` sets any property of the object's hairdyn settings by name (enum values
case-insensitive; vectors as x,y,z; objects and images by name; colliders as a
comma-separated list of objects); a name shared by two groups is qualified: strands.damping,
collision.damping. Exit codes: 0 success, 1 the simulation failed (message on stderr, the
report still written when possible), 2 bad command line (unknown object, parameter or value).
"""
import argparse
import json
import struct
import sys
from pathlib import Path

USAGE_ERROR = 2
RUN_ERROR = 1


class UsageError(Exception):
    pass


def _arguments(argv):
    parser = argparse.ArgumentParser(
        prog="hairdyn", description="Run hairdyn on a hair object of a .blend, headless.")
    parser.add_argument("--blend", help="open this .blend first (bpy module; the blender "
                                        "binary opens the file given before --python)")
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("run", help="simulate a frame range into the output objects")
    bake = commands.add_parser("bake", help="bake a frame range to the cache (same options as "
                                            "run, plus --cache and --resume)")
    for command in (run, bake):
        command.add_argument("--object", required=True, help="name of the hair object")
        command.add_argument("--frames", nargs=2, type=int, metavar=("START", "END"),
                             help="frame range (default: the object's hairdyn frame range)")
        command.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                             help="set a hairdyn parameter by its property name (repeatable)")
        command.add_argument("--report", help="write the JSON report here (default: stdout)")
        command.add_argument("--save", help="save the .blend with the results here")
    bake.add_argument("--cache", help="cache folder (default: the object's cache folder; a "
                                      "subfolder named after the object is used)")
    bake.add_argument("--resume", action="store_true",
                      help="continue after the last baked frame instead of starting over")
    export = commands.add_parser("export", help="write the baked frames of the output hair to "
                                                "Alembic (.abc) or USD (.usd/.usda/.usdc)")
    export.add_argument("--object", required=True, help="name of the hair object")
    export.add_argument("--file", required=True, help="the file to write; its suffix picks the format")
    export.add_argument("--cache", help="the cache folder given to bake (default: the object's)")
    export.set_defaults(set=[], frames=None)
    _wedge().add_arguments(commands.add_parser(
        "wedge", help="bake a table of parameter sets in parallel on Dask (see wedge.py)"))
    return parser.parse_args(argv)


def _wedge():
    """wedge.py, loaded without the hairdyn package (whose import needs bpy): the wedge's
    driver runs in any Python with Dask."""
    import importlib.util

    if "hairdyn_wedge" not in sys.modules:
        spec = importlib.util.spec_from_file_location("hairdyn_wedge",
                                                      Path(__file__).with_name("wedge.py"))
        sys.modules["hairdyn_wedge"] = module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    return sys.modules["hairdyn_wedge"]


def _as_stored(value, kind):
    """`value` as Blender stores it: FLOAT properties, and their bounds, are single precision,
    so 0.001 typed for a minimum of 0.001 compares equal to it."""
    if kind != 'FLOAT' or not abs(value) <= 3.4e38:
        return value
    return struct.unpack("f", struct.pack("f", value))[0]


def _parse_value(prop, text, unit=""):
    """Text -> a value for the RNA property `prop` (in `unit`, named when out of range), or
    UsageError."""
    kind = prop.type
    if kind == 'BOOLEAN':
        lowered = text.strip().lower()
        if lowered in ("1", "true", "yes", "on"):
            return True
        if lowered in ("0", "false", "no", "off"):
            return False
        raise UsageError(f"{prop.identifier} must be true or false, not '{text}'")
    if kind in ('INT', 'FLOAT'):
        parse = int if kind == 'INT' else float
        texts = text.split(",")
        if len(texts) != max(prop.array_length, 1):
            raise UsageError(f"{prop.identifier} needs {max(prop.array_length, 1)} value(s), "
                             f"not '{text}'")
        try:
            values = [parse(t) for t in texts]
        except ValueError:
            raise UsageError(f"{prop.identifier} must be {'an integer' if kind == 'INT' else 'a number'}, "
                             f"not '{text}'") from None
        for value in values:
            if not (prop.hard_min <= _as_stored(value, kind) <= prop.hard_max):
                unit_text = f" {unit}" if unit else ""
                raise UsageError(f"{prop.identifier} must be between {prop.hard_min:g} and "
                                 f"{prop.hard_max:g}{unit_text}, not {text}")
        return values if prop.array_length else values[0]
    if kind == 'ENUM':
        identifiers = [item.identifier for item in prop.enum_items]
        for identifier in identifiers:
            if identifier.lower() == text.strip().lower():
                return identifier
        raise UsageError(f"{prop.identifier} must be one of {', '.join(i.lower() for i in identifiers)}, "
                         f"not '{text}'")
    if kind == 'POINTER':
        import bpy

        kind_name = prop.fixed_type.identifier  # Object, Image
        datablocks = {"Object": bpy.data.objects, "Image": bpy.data.images}.get(kind_name)
        if datablocks is None:
            raise UsageError(f"{prop.identifier} cannot be set from the command line")
        found = datablocks.get(text)
        if found is None:
            raise UsageError(f"{prop.identifier}: there is no {kind_name.lower()} named '{text}'")
        return found
    if kind == 'STRING':
        return text
    raise UsageError(f"{prop.identifier} cannot be set from the command line")


def _settable(group, prefix=""):
    """{qualified name: (owner group, RNA property)} of every settable property, nested groups
    (strands.k_theta, collision.stiffness) included."""
    import bpy

    found = {}
    for prop in group.bl_rna.properties:
        name = prop.identifier
        if name in ("rna_type", "name"):
            continue
        value = getattr(group, name)
        if prop.type == 'POINTER' and isinstance(value, bpy.types.PropertyGroup):
            found.update(_settable(value, f"{prefix}{name}."))
        else:
            found[prefix + name] = (group, prop)
    return found


def _resolve(settable, name):
    """A qualified name, or an unqualified one that names exactly one property."""
    if name in settable:
        return settable[name]
    matches = [key for key in settable if key.rsplit(".", 1)[-1] == name]
    if len(matches) == 1:
        return settable[matches[0]]
    if matches:
        raise UsageError(f"parameter '{name}' is ambiguous: use one of {', '.join(matches)}")
    raise UsageError(f"unknown parameter '{name}'; known: {', '.join(sorted(settable))}")


def apply_settings(settings, assignments):
    """Apply NAME=VALUE strings to a hairdyn settings PropertyGroup. NAME is a property name,
    qualified by its group where needed (strands.damping, collision.damping)."""
    from hairdyn import native, parameters

    settable = _settable(settings)
    for assignment in assignments:
        name, sep, text = assignment.partition("=")
        name = name.strip()
        if not sep:
            raise UsageError(f"--set needs NAME=VALUE, not '{assignment}'")
        group, prop = _resolve(settable, name)
        if prop.type == 'COLLECTION':
            _set_colliders(group, prop, text)
            continue
        value = _parse_value(prop, text, parameters.shown_unit(group, prop.identifier,
                                                               native.load()))
        try:
            setattr(group, prop.identifier, value)
        except (TypeError, ValueError) as error:
            raise UsageError(f"{name}: {error}") from None


def _set_colliders(group, prop, text):
    """colliders=A,B: the list of extra collider objects."""
    import bpy

    names = [n.strip() for n in text.split(",") if n.strip()]
    missing = [n for n in names if bpy.data.objects.get(n) is None]
    if missing:
        raise UsageError(f"{prop.identifier}: there is no object named {', '.join(missing)}")
    items = getattr(group, prop.identifier)
    items.clear()
    for name in names:
        items.add().object = bpy.data.objects[name]


def _ensure_addon():
    """Import and register the hairdyn package that holds this file."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
    import bpy
    import hairdyn

    if not hasattr(bpy.types.Object, "hairdyn"):
        hairdyn.register()
    return hairdyn


def _progress(frame, ms):
    print(f"hairdyn: frame {frame} ({ms:.2f} ms)", flush=True)


def _bake(args, obj, start, end):
    """Bake into the cache, one progress line per frame; returns the report."""
    import bpy
    from hairdyn import bake

    settings = obj.hairdyn
    settings.frame_start, settings.frame_end = start, end
    if args.cache:
        settings.cache_directory = str(Path(args.cache).resolve())
    resume_after = end if args.resume else None
    runner = bake.start_bake(bpy.context, obj, resume_after, show_frames=False)
    try:
        while not runner.done:
            _progress(*runner.advance())
    finally:
        report = bake.finish_bake(runner)
    report["cache"] = str(runner.cache.directory)
    return report


def _export(args, obj):
    """cli.py export: the bake in --cache (or the object's) to --file."""
    import bpy
    from hairdyn import export

    if args.cache:
        obj.hairdyn.cache_directory = str(Path(args.cache).resolve())
    result = export.export_bake(bpy.context, obj, args.file)
    print(json.dumps(result, indent=2))
    return 0


def main(argv):
    """Runs the command line; returns the exit code. Every failure, whatever raised it, is one
    line on stderr and exit code 1 (2 for a bad command line): under the blender binary an
    exception escaping this function would still end the process with exit code 0."""
    try:
        args = _arguments(argv)
    except SystemExit as exit_:
        return USAGE_ERROR if exit_.code else 0
    if args.command == "wedge":
        return _wedge().main(args)
    try:
        return _main(args)
    except UsageError as error:
        print(f"hairdyn: error: {error}", file=sys.stderr)
        return USAGE_ERROR
    except Exception as error:  # noqa: BLE001 - the add-on's error boundary (errors.py)
        from hairdyn import errors

        if errors.is_internal(error):
            errors.print_traceback(error)
        print(f"hairdyn: error: {errors.message(error)}", file=sys.stderr)
        return RUN_ERROR


def _main(args):
    import bpy

    hairdyn = _ensure_addon()
    from hairdyn import simulation

    if args.blend:
        if not Path(args.blend).is_file():
            raise UsageError(f"there is no .blend file at '{args.blend}'")
        bpy.ops.wm.open_mainfile(filepath=str(Path(args.blend).resolve()))
    obj = bpy.data.objects.get(args.object)
    if obj is None:
        hair = [o.name for o in bpy.data.objects if hairdyn.bridge.is_hair_object(o)]
        raise UsageError(f"there is no object named '{args.object}'; hair objects: "
                         f"{', '.join(hair) or 'none'}")
    apply_settings(obj.hairdyn, args.set)
    start, end = args.frames or (obj.hairdyn.frame_start, obj.hairdyn.frame_end)

    if args.command == "export":
        return _export(args, obj)
    report = _bake(args, obj, start, end) if args.command == "bake" else \
        simulation.run(bpy.context, obj, start, end, on_frame=_progress, show_frames=False)
    text = json.dumps(report, indent=2)
    if args.report:
        Path(args.report).write_text(text + "\n")
        print(f"hairdyn: report written to {args.report}")
    else:
        print(text)
    if args.save:
        bpy.ops.wm.save_as_mainfile(filepath=str(Path(args.save).resolve()), copy=True)
    if report["nan_frames"]:
        print(f"hairdyn: error: {report['nan_frames']} frame(s) were not finite", file=sys.stderr)
        return RUN_ERROR
    return 0


def _argv():
    """Arguments after '--' inside Blender, else the script's own arguments."""
    return sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]


if __name__ == "__main__":
    code = main(_argv())
    if code:
        sys.exit(code)
