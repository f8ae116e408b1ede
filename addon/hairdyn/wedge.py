"""Parameter wedges: many bakes of one hair object, in parallel on Dask distributed.

    blender -b --python addon/hairdyn/cli.py -- wedge scene.blend --object Hair --out OUT
        --vary k_theta=0.1,0.2 --vary damping=0.5,1 [--table sets.csv|sets.json]
        [--frames 1 24] [--set name=value] [--workers 2 | --scheduler tcp://HOST:PORT]
    python addon/hairdyn/cli.py wedge ...      (any Python with dask.distributed)

The parameter sets are the rows of a table (CSV with a header of parameter names, or JSON: a
list of {name: value}) times the product of the --vary lists; --set applies to all. Each set is
one Dask task, and each task one headless bake in its own process (`blender -b scene.blend
--python wedge.py -- task SPEC`, or the bpy module's Python), into OUT/set_NNN/cache, with its
report in OUT/set_NNN/report.json and its last frame rendered (Cycles, few samples) to
OUT/set_NNN/last_frame.png. A failed set is recorded with its message and the others go on. A
re-run skips the sets already done with the same parameters. Then OUT/summary.json holds every
set's parameters, status, message and report, and OUT/contact_sheet.png the last frames side
by side, in the summary's order.

Importing this module needs neither bpy nor Dask: the driver runs wherever Dask is, the tasks
inside Blender.
"""

import csv
import itertools
import json
import os
import subprocess
import sys
from pathlib import Path

SUMMARY = "summary.json"
SHEET = "contact_sheet.png"
RESULT = "result.json"
LAST_FRAME = "last_frame.png"
TASK_TIMEOUT_S = 3600
THIS_FILE = Path(__file__).resolve()
CLI = THIS_FILE.parent / "cli.py"


class WedgeError(Exception):
    pass


# ---- the parameter sets ------------------------------------------------------------------------


def read_table(path):
    """Parameter sets from a CSV file (header: parameter names) or a JSON list of objects;
    values as text, as `--set` takes them."""
    path = Path(path)
    if not path.is_file():
        raise WedgeError(f"there is no parameter table at '{path}'")
    if path.suffix.lower() == ".json":
        try:
            rows = json.loads(path.read_text())
        except ValueError as error:
            raise WedgeError(f"the table '{path}' is not valid JSON: {error}") from None
        if not isinstance(rows, list) or not all(isinstance(row, dict) for row in rows):
            raise WedgeError(f"the table '{path}' must be a JSON list of {{name: value}} objects")
    else:
        with open(path, newline="") as file:
            rows = list(csv.DictReader(file))
    sets = []
    for number, row in enumerate(rows, 1):
        if any(key is None or not str(key).strip() for key in row):
            raise WedgeError(f"row {number} of '{path}' has more values than the header names")
        sets.append({str(key).strip(): _text(value) for key, value in row.items()})
    return sets


def _text(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return ",".join(str(v) for v in value)
    return str(value).strip()


def parse_vary(texts):
    """['k_theta=0.1,0.2', ...] -> [('k_theta', ['0.1', '0.2']), ...]."""
    axes = []
    for text in texts:
        name, sep, values = text.partition("=")
        values = [v.strip() for v in values.split(",") if v.strip()]
        if not sep or not name.strip() or not values:
            raise WedgeError(f"--vary needs NAME=V1,V2,..., not '{text}'")
        axes.append((name.strip(), values))
    return axes


def parameter_sets(table=None, vary=()):
    """The rows of the table (or one empty row) times the product of the --vary axes."""
    rows = read_table(table) if table else [{}]
    axes = parse_vary(vary)
    names = [name for name, _ in axes]
    sets = [
        {**row, **dict(zip(names, values))}
        for row in rows
        for values in itertools.product(*(v for _, v in axes))
    ]
    if not sets or sets == [{}]:
        raise WedgeError("no parameter sets: give --table FILE and/or --vary NAME=V1,V2")
    return sets


# ---- one task: a bake in its own Blender process -----------------------------------------------


def host_command(blender=None, python=None):
    """How a task starts Blender: ['blender', '-b'] style for the binary, or [python] for a
    Python with the bpy module."""
    if python:
        return {"python": str(python)}
    return {"blender": str(blender or "blender")}


def task_command(host, spec_path):
    script = [str(THIS_FILE), "--", "task", str(spec_path)]
    if "python" in host:
        return [host["python"], str(THIS_FILE), "task", str(spec_path)]
    return [
        host["blender"],
        "-b",
        "--factory-startup",
        "--python-exit-code",
        "1",
        "--python",
        *script,
    ]


def prepare_task(spec, host):
    """Write the set's spec into its folder (dropping an older result); the command that bakes
    it. The command is all a Dask worker runs (subprocess.run), so no hairdyn code travels."""
    folder = Path(spec["folder"])
    folder.mkdir(parents=True, exist_ok=True)
    spec_path = folder / "spec.json"
    spec_path.write_text(json.dumps(spec, indent=2))
    (folder / RESULT).unlink(missing_ok=True)
    return task_command(host, spec_path)


def task_result(spec, process=None, error=None):
    """The set's result once its process ended (a CompletedProcess) or its task failed
    (`error`): what the bake wrote in result.json, else a failure naming the cause."""
    folder = Path(spec["folder"])
    returncode, output = None, str(error or "")
    if process is not None:
        (folder / "log.txt").write_text(process.stdout + process.stderr)
        returncode, output = process.returncode, process.stderr + process.stdout
    result_path = folder / RESULT
    if result_path.is_file():
        result = json.loads(result_path.read_text())
    else:  # the process died before it could say
        result = {
            "status": "failed",
            "report": None,
            "image": None,
            "message": _error_line(output)
            or output.strip()[-300:]
            or f"the bake process ended with exit code {returncode}",
        }
    result.update(name=spec["name"], parameters=spec["parameters"], returncode=returncode)
    result_path.write_text(json.dumps(result, indent=2))
    return result


def _child_environment():
    """Python's copy of the environment (bpy 5.2 puts its own OCIO config into the C one)."""
    return dict(os.environ)


def _error_line(output):
    lines = [line for line in output.splitlines() if "error" in line.lower()]
    return lines[-1].strip() if lines else ""


def _in_blender_task(spec_path):
    """Inside Blender: open the scene, bake with cli.py's bake, render the last frame; writes
    result.json. Exit code 0 done, 1 failed."""
    spec = json.loads(Path(spec_path).read_text())
    folder = Path(spec["folder"])
    sys.path.insert(0, str(THIS_FILE.parent.parent))
    import bpy

    from hairdyn import cli

    bpy.ops.wm.open_mainfile(filepath=spec["blend"])
    report_path = folder / "report.json"
    report_path.unlink(missing_ok=True)
    argv = [
        "bake",
        "--object",
        spec["object"],
        "--cache",
        str(folder / "cache"),
        "--report",
        str(report_path),
    ]
    if spec.get("frames"):
        argv += ["--frames", *map(str, spec["frames"])]
    for name, value in {**spec.get("common", {}), **spec["parameters"]}.items():
        argv += ["--set", f"{name}={value}"]
    import contextlib
    import io

    errors = io.StringIO()
    with contextlib.redirect_stderr(errors):
        code = cli.main(argv)
    sys.stderr.write(errors.getvalue())
    result = {"status": "failed", "message": None, "report": None, "image": None}
    if report_path.is_file():
        result["report"] = json.loads(report_path.read_text())
    if code != 0:
        result["message"] = (
            _error_line(errors.getvalue()).removeprefix("hairdyn: error: ")
            or f"the bake ended with exit code {code}"
        )
    else:
        try:
            result["image"] = str(render_last_frame(bpy.context, spec, folder / LAST_FRAME))
            result["status"] = "done"
        except RuntimeError as error:
            result["message"] = f"the render of the last frame failed: {error}"
    (folder / RESULT).write_text(json.dumps(result, indent=2))
    return 0 if result["status"] == "done" else 1


def render_last_frame(context, spec, path, size=160, samples=4):
    """The bake's last frame, played back from its cache, rendered by Cycles at few samples
    (no GPU or display needed) from the scene's camera, or from the front when it has none."""
    import bpy

    scene = context.scene
    obj = bpy.data.objects[spec["object"]]
    report = json.loads((Path(spec["folder"]) / "report.json").read_text())
    obj.hairdyn.cache_directory = str(Path(spec["folder"]) / "cache")
    obj.hairdyn.enabled = obj.hairdyn.use_cache = True
    scene.frame_set(report["frame_end"])
    if scene.camera is None:
        _add_front_camera(scene, obj)
    render = scene.render
    render.engine = 'CYCLES'
    scene.cycles.samples = samples
    scene.cycles.device = 'CPU'
    render.resolution_x = render.resolution_y = size
    render.resolution_percentage = 100
    render.image_settings.file_format = 'PNG'
    render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    if not path.is_file():
        raise RuntimeError(f"no image at {path}")
    return path


def _add_front_camera(scene, obj):
    """A camera looking at the hair object's bounds along +y (Blender's front view)."""
    import bpy
    from mathutils import Vector

    corners = [obj.matrix_world @ Vector(corner) for corner in obj.bound_box]
    low = Vector([min(c[i] for c in corners) for i in range(3)])
    high = Vector([max(c[i] for c in corners) for i in range(3)])
    camera = bpy.data.objects.new("hairdyn wedge camera", bpy.data.cameras.new("hairdyn wedge"))
    scene.collection.objects.link(camera)
    camera.data.type = 'ORTHO'
    camera.data.ortho_scale = 1.6 * max(high - low)
    camera.location = ((low + high) / 2) - Vector((0.0, 3.0 * max(high - low) + 1.0, 0.0))
    camera.rotation_euler = (1.5707963, 0.0, 0.0)
    scene.camera = camera


# ---- the contact sheet -------------------------------------------------------------------------


def _in_blender_sheet(sheet_spec_path):
    """Inside Blender: tile the listed PNGs (None: a grey tile) into one PNG."""
    import numpy as np

    import bpy

    spec = json.loads(Path(sheet_spec_path).read_text())
    tiles = []
    for path in spec["images"]:
        if path and Path(path).is_file():
            image = bpy.data.images.load(path)
            width, height = image.size
            pixels = np.empty(width * height * 4, dtype=np.float32)
            image.pixels.foreach_get(pixels)
            tiles.append(pixels.reshape(height, width, 4))
            bpy.data.images.remove(image)
        else:
            tiles.append(None)
    size = max((t.shape[:2] for t in tiles if t is not None), default=(64, 64))
    columns = int(np.ceil(np.sqrt(len(tiles))))
    rows = int(np.ceil(len(tiles) / columns))
    sheet = np.ones((rows * size[0], columns * size[1], 4), dtype=np.float32)
    for index, tile in enumerate(tiles):
        top = (rows - 1 - index // columns) * size[0]  # Blender's rows run bottom-up
        left = (index % columns) * size[1]
        block = sheet[top : top + size[0], left : left + size[1]]
        if tile is None:
            block[..., :3] = 0.5  # a failed set
        else:
            block[: tile.shape[0], : tile.shape[1]] = tile
    image = bpy.data.images.new("hairdyn contact sheet", sheet.shape[1], sheet.shape[0], alpha=True)
    image.pixels.foreach_set(sheet.ravel())
    image.filepath_raw = spec["out"]
    image.file_format = 'PNG'
    image.save()
    return 0


# ---- the driver --------------------------------------------------------------------------------


def _client(scheduler, workers):
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise WedgeError(
            "cli.py wedge needs Dask distributed in this Python (Debian: apt "
            "install python3-distributed; pip: dask distributed)"
        ) from None
    if scheduler:
        return Client(scheduler, timeout="20s"), None
    cluster = LocalCluster(
        n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
    )
    return Client(cluster), cluster


def _done(folder, parameters, common):
    """The result of a set baked before with these parameters, or None."""
    try:
        result = json.loads((folder / RESULT).read_text())
        spec = json.loads((folder / "spec.json").read_text())
    except (OSError, ValueError):
        return None
    if (
        result.get("status") != "done"
        or spec.get("parameters") != parameters
        or spec.get("common") != common
    ):
        return None
    return result


def run_wedge(
    blend, obj, sets, out_dir, *, frames=None, common=None, host=None, scheduler=None, workers=2
):
    """Bake every parameter set on Dask (a local cluster of `workers` processes, or the
    scheduler at `scheduler`); returns the summary, also written to out_dir/summary.json."""
    out_dir = Path(out_dir).resolve()
    out_dir.mkdir(parents=True, exist_ok=True)
    host = host or host_command()
    common = dict(common or {})
    specs, results = [], {}
    for index, parameters in enumerate(sets):
        name = f"set_{index:03d}"
        spec = {
            "name": name,
            "blend": str(Path(blend).resolve()),
            "object": obj,
            "frames": list(frames) if frames else None,
            "parameters": parameters,
            "common": common,
            "folder": str(out_dir / name),
        }
        specs.append(spec)
        previous = _done(out_dir / name, parameters, common)
        if previous is not None:
            results[name] = {**previous, "skipped": True}
    pending = [spec for spec in specs if spec["name"] not in results]
    if pending:
        client, cluster = _client(scheduler, workers)
        try:
            futures = [
                client.submit(
                    subprocess.run,
                    prepare_task(spec, host),
                    capture_output=True,
                    text=True,
                    timeout=TASK_TIMEOUT_S,
                    pure=False,
                )
                for spec in pending
            ]
            for spec, future in zip(pending, futures):
                try:
                    result = task_result(spec, process=future.result())
                except Exception as error:  # noqa: BLE001 (timeout, lost worker: that set failed)
                    result = task_result(spec, error=f"the Dask task failed: {error!r}")
                results[spec["name"]] = {**result, "skipped": False}
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    entries = [
        {
            "name": spec["name"],
            "parameters": spec["parameters"],
            "folder": spec["folder"],
            **{k: v for k, v in results[spec["name"]].items() if k not in ("name", "parameters")},
        }
        for spec in specs
    ]
    summary = {
        "blend": str(Path(blend).resolve()),
        "object": obj,
        "common": common,
        "sets": entries,
        "done": sum(e["status"] == "done" for e in entries),
        "failed": sum(e["status"] != "done" for e in entries),
        "baked_now": sum(not e["skipped"] for e in entries),
        "contact_sheet": None,
    }
    sheet = make_contact_sheet(
        host, [e.get("image") if e["status"] == "done" else None for e in entries], out_dir
    )
    summary["contact_sheet"] = str(sheet) if sheet else None
    (out_dir / SUMMARY).write_text(json.dumps(summary, indent=2))
    return summary


def make_contact_sheet(host, images, out_dir):
    """One Blender process tiles the last frames into out_dir/contact_sheet.png; its path, or
    None when no set has an image."""
    if not any(images):
        return None
    spec_path = out_dir / "contact_sheet.json"
    out = out_dir / SHEET
    spec_path.write_text(json.dumps({"images": images, "out": str(out)}))
    command = task_command(host, spec_path)
    command[command.index("task")] = "sheet"
    process = subprocess.run(
        command, capture_output=True, text=True, timeout=600, env=_child_environment()
    )
    if process.returncode != 0 or not out.is_file():
        raise WedgeError(
            f"the contact sheet was not made: {_error_line(process.stderr + process.stdout)}"
        )
    return out


def add_arguments(parser):
    """The `wedge` subcommand's options (cli.py wedge)."""
    parser.add_argument("blend", help="the .blend file to bake")
    parser.add_argument("--object", required=True, help="name of the hair object")
    parser.add_argument("--out", required=True, help="output folder (one subfolder per set)")
    parser.add_argument("--table", help="CSV (header: parameter names) or JSON list of sets")
    parser.add_argument(
        "--vary",
        action="append",
        default=[],
        metavar="NAME=V1,V2,...",
        help="a parameter's values; several --vary make their product",
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="a parameter for every set (repeatable)",
    )
    parser.add_argument("--frames", nargs=2, type=int, metavar=("START", "END"))
    parser.add_argument("--workers", type=int, default=2, help="local cluster size (default 2)")
    parser.add_argument("--scheduler", help="tcp://HOST:PORT of an existing Dask scheduler")
    parser.add_argument(
        "--blender",
        help="Blender binary the tasks run (default: the host's own, else 'blender' on PATH)",
    )
    parser.add_argument("--python", help="a Python with the bpy module, instead of --blender")


def main(args):
    """Run the `wedge` subcommand from parsed arguments; exit code 0 all done, 1 a set
    failed, 2 bad command line."""
    try:
        common = {}
        for assignment in args.set:
            name, sep, value = assignment.partition("=")
            if not sep:
                raise WedgeError(f"--set needs NAME=VALUE, not '{assignment}'")
            common[name.strip()] = value
        sets = parameter_sets(args.table, args.vary)
        if not Path(args.blend).is_file():
            raise WedgeError(f"there is no .blend file at '{args.blend}'")
        if args.workers < 1:
            raise WedgeError("--workers must be at least 1")
    except WedgeError as error:
        print(f"hairdyn: error: {error}", file=sys.stderr)
        return 2
    try:
        summary = run_wedge(
            args.blend,
            args.object,
            sets,
            args.out,
            frames=args.frames,
            common=common,
            host=host_command(args.blender, args.python)
            if args.blender or args.python
            else own_host(),
            scheduler=args.scheduler,
            workers=args.workers,
        )
    except WedgeError as error:
        print(f"hairdyn: error: {error}", file=sys.stderr)
        return 1
    for entry in summary["sets"]:
        state = entry["status"] + (" (already done)" if entry["skipped"] else "")
        message = f": {entry['message']}" if entry.get("message") else ""
        print(f"hairdyn: {entry['name']} {entry['parameters']} {state}{message}")
    print(
        f"hairdyn: {summary['done']} done, {summary['failed']} failed; summary in "
        f"{Path(args.out) / SUMMARY}"
    )
    return 1 if summary["failed"] else 0


def own_host():
    """The Blender running this driver: the blender binary, or this Python when it has the bpy
    module; else None (the tasks run the 'blender' on PATH)."""
    import importlib.util

    bpy = sys.modules.get("bpy")
    if bpy is not None and bpy.app.binary_path:
        return host_command(blender=bpy.app.binary_path)
    if importlib.util.find_spec("bpy") is not None:
        return host_command(python=sys.executable)
    return None


if __name__ == "__main__":
    arguments = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
    if len(arguments) == 2 and arguments[0] in ("task", "sheet"):
        run = _in_blender_task if arguments[0] == "task" else _in_blender_sheet
        sys.exit(run(arguments[1]))
    print("wedge.py is run by 'cli.py wedge'", file=sys.stderr)
    sys.exit(2)
