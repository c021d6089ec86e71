"""The ``pvcloth`` command: parse arguments, load a scene, call the library."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from pvcloth.errors import InputError, PvclothError
from pvcloth.scene.files import load_scene
from pvcloth.scene.overrides import parse_assignment, parse_value
from pvcloth.scene.parts import MEASURING_INTEGRATORS, STABILITY_POLICIES
from pvcloth.scene.validation import real
from pvcloth.signals import Terminated, check, deferred, handled


def _add_overrides(parser: argparse.ArgumentParser, one_integrator: bool = True) -> None:
    """The scene argument and the options that change it; ``one_integrator``
    False leaves ``--integrator`` out (for commands that take several)."""
    parser.add_argument("scene", help="scene file (TOML), e.g. data/scenes/hanging.toml")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="change a scene key, e.g. --set springs.structural.stiffness=2000 "
        "(dotted keys as in the scene file; repeat for more)",
    )
    parser.add_argument(
        "--view",
        choices=("iso", "front", "side", "top"),
        help="the same as --set camera.view=...: the direction the camera looks from "
        "(an explicit camera: --set camera.position=[X,Y,Z] --set camera.focal_point=[X,Y,Z])",
    )
    if one_integrator:
        parser.add_argument("--integrator", help="the same as --set solver.integrator=NAME")
    parser.add_argument("--dt", type=float, help="the same as --set solver.dt=SECONDS")
    parser.add_argument(
        "--tolerance",
        type=float,
        metavar="METRES",
        help="the same as --set solver.tolerance=METRES: steps chosen for this error "
        "(per simulated second) by an integrator that measures it: "
        + ", ".join(MEASURING_INTEGRATORS)
        + ", or auto (the cheapest of them on this scene)",
    )
    parser.add_argument(
        "--stability",
        choices=STABILITY_POLICIES,
        help="the same as --set solver.stability=...: a step above the stable one is refused, "
        "split into substeps, or run anyway",
    )


def _add_colors(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--color",
        metavar="FIELD",
        help="colour the cloth by stretch, speed, force, energy or error (against a fine RK4 "
        "reference run alongside), with a scalar bar in its unit",
    )
    parser.add_argument("--clim", metavar="LOW,HIGH", help="fixed colour range (default: grows)")
    parser.add_argument("--cmap", metavar="NAME", help="colour map (matplotlib's names)")


def _scene(args):
    """The scene file with the command line's changes, in the dotted-key
    dialect every scene change uses (:mod:`pvcloth.scene.overrides`)."""
    changes = {}
    for item in args.set:
        key, text = parse_assignment(item)
        changes[key] = parse_value(text)
    for key, value in (
        ("solver.integrator", getattr(args, "integrator", None)),
        ("solver.dt", args.dt),
        ("solver.stability", args.stability),
        ("solver.tolerance", args.tolerance),
        ("camera.view", args.view),
    ):
        if value is not None:
            changes[key] = value
    return load_scene(args.scene).with_overrides(changes)


def _simulation(args):
    from pvcloth.physics.simulation import Simulation

    return Simulation(_scene(args))


def cmd_info(args) -> None:
    from pvcloth.info import describe

    print(describe(_simulation(args)))


#: The commands that run a simulation (and may compile the kernels first).
SIMULATING = ("run", "info", "simulate", "render", "compare", "export", "tradeoff", "sweep")


def cmd_simulate(args) -> None:
    from pvcloth.compilation import compile_seconds
    from pvcloth.progress import frame_bar

    seconds = real("--seconds", args.seconds, minimum=0.0, exclusive=True, error=InputError)
    fps = real("--fps", args.fps, minimum=0.0, exclusive=True, maximum=1000.0, error=InputError)
    sim = _simulation(args)
    frames = max(1, round(seconds * fps))
    start, compiled = time.perf_counter(), compile_seconds()
    # frames + 1: frame 0 is the start; each later one is seconds / frames on.
    loop = sim.frames(frames + 1, frames / seconds)
    for _ in frame_bar(loop, frames + 1, f"simulating {sim.scene.name}", enabled=not args.quiet):
        check()
    compiling = compile_seconds() - compiled  # a first run's: not the simulation's speed
    wall = time.perf_counter() - start - compiling
    energy = sim.energy()
    steps = f"{sim.dt:.3g} s"
    if sim.controller is not None:
        stats = sim.stats
        steps = (
            f"adaptive length (tolerance {sim.controller.tolerance:g} m: {stats['shortest']:.3g}"
            f" to {stats['longest']:.3g} s, mean {stats['mean']:.3g} s, last {stats['last']:.3g}"
            f" s; {stats['rejected']} rejected and retried)"
        )
    z = sim.positions[:, 2]
    centre = sim.model.mass @ z / sim.model.mass.sum()
    print(
        f"simulated {sim.time:.4g} s in {sim.steps} steps of {steps} "
        f"({sim.integrator.name}) in {wall:.3g} s wall ({sim.time / wall:.3g} x real time)"
        + (f", besides {compiling:.3g} s compiling the kernels\n" if compiling > 0 else "\n")
        + f"lowest point z = {z.min():.4g} m, centre of mass z = {centre:.4g} m\n"
        f"energy: kinetic {energy['kinetic']:.4g} J, potential {energy['potential']:.4g} J"
    )


def cmd_compare(args) -> None:
    from pvcloth.visual.colors import check_field
    from pvcloth.visual.compare import compare, parse_list, parse_steps
    from pvcloth.visual.movie import parse_size

    check_field(args.color)
    integrators = parse_list("integrators", args.integrators)
    dts = None if args.dts is None else parse_steps(args.dts)
    size = None if args.size is None else parse_size(args.size)
    stats = compare(
        _scene(args),
        args.output,
        integrators,
        dts=dts,
        frames=args.frames,
        fps=args.fps,
        size=size,
        color=args.color,
        progress=not args.quiet,
    )
    print(f"wrote {stats.path} ({stats.frames} frames)")
    for panel in stats.panels:
        print("  " + panel.label().replace("\n", "; "))


def cmd_render(args) -> None:
    from pvcloth.visual.colors import check_cmap, check_field, parse_clim
    from pvcloth.visual.movie import parse_size, render

    check_field(args.color)
    check_cmap(args.cmap)
    clim = None if args.clim is None else parse_clim(args.clim)
    sim = _simulation(args)
    stats = render(
        sim,
        args.output,
        frames=args.frames,
        fps=args.fps,
        size=parse_size(args.size),
        progress=not args.quiet,
        color=args.color,
        clim=clim,
        cmap=args.cmap,
    )
    ms = stats.medians_ms()
    print(
        f"wrote {stats.path} ({stats.frames} frames, {sim.time:.3g} s simulated); median ms "
        f"per frame: physics {ms['physics']:.1f}, drawing {ms['drawing']:.1f}, "
        f"encoding {ms['encoding']:.1f}"
    )
    for note in stats.notes:
        print(f"note: {note}")


def cmd_run(args) -> None:
    from pvcloth.visual.movie import parse_size

    with deferred():  # a signal inside VTK's module set-up crashed the process
        from pvcloth.visual.window import ClothApp, check_display
    check_display()  # before building anything: VTK cannot say it has no screen
    sim = _simulation(args)
    with deferred():  # a signal inside VTK's module set-up crashed the process
        app = ClothApp(sim, fps=args.fps, window_size=parse_size(args.size))
    app.run()


def cmd_export(args) -> None:
    from pvcloth.io.timeseries import export

    sim = _simulation(args)
    where = export(sim, args.output, frames=args.frames, fps=args.fps, progress=not args.quiet)
    print(f"wrote {args.frames} frames ({sim.time:.3g} s simulated) to {where}")


def cmd_tradeoff(args) -> None:
    from pvcloth.studies import tradeoff

    scene = load_scene(args.scene)
    if args.resolution:
        scene = scene.with_resolution(args.resolution)
    integrators = args.integrators.split(",") if args.integrators else None
    steps = [float(v) for v in args.steps.split(",")] if args.steps else None
    tolerances = None
    if args.tolerances is not None:
        tolerances = [
            real("--tolerances", parse_value(v), minimum=1e-12, maximum=1.0, error=InputError)
            for v in args.tolerances.split(",")
            if v.strip() and args.tolerances.strip() != "none"
        ]
    expected = tradeoff.estimate_seconds(
        scene, integrators, steps, duration=args.duration, tolerances=tolerances
    )
    nx, ny = scene.cloth.resolution
    note = f"pvcloth: about {_duration(expected)} for these runs at {nx}x{ny} points"
    if expected > 90:
        shorter = ["--resolution 16"] if max(nx, ny) > 16 else []
        shorter += ["fewer --integrators", "fewer --steps", "a shorter --duration"]
        note += f" (to make it shorter: {', '.join(shorter)})"
    print(note, file=sys.stderr, flush=True)
    runs = tradeoff.measure(
        scene,
        integrators=integrators,
        steps=steps,
        duration=args.duration,
        tolerances=tolerances,
        progress=not args.quiet,
    )
    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    tradeoff.write_csv(runs, out / "tradeoff.csv")
    tradeoff.plot(
        runs, out / "tradeoff.png", f"{scene.name}, {nx}x{ny} points, {args.duration:g} s simulated"
    )
    print(tradeoff.table(runs))
    print(f"wrote {out / 'tradeoff.csv'} and {out / 'tradeoff.png'}")


def _duration(seconds: float) -> str:
    """A wall time as a person says it: '40 s', '3 min', '1.5 h'."""
    if seconds < 90:
        return f"{max(seconds, 1):.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def cmd_sweep(args) -> None:
    from pvcloth.studies import sweep

    scene = load_scene(args.scene)
    sets = sweep.parse_sets(args.set or [])
    if not sets:
        raise sweep.SweepError("give at least one --set KEY=VALUES")
    out = Path(args.output)
    rows = sweep.run_sweep(
        scene,
        sets,
        out,
        duration=args.duration,
        scheduler=args.scheduler,
        workers=args.workers,
        progress=not args.quiet,
    )
    axes = args.axes.split(",") if args.axes else None
    sweep.plot(rows, sets, out / "sweep.png", axes)
    print(sweep.summary(rows))
    print(f"wrote {out / 'sweep.csv'} ({len(rows)} runs) and {out / 'sweep.png'}")


def build_parser() -> argparse.ArgumentParser:
    from pvcloth import __version__

    parser = argparse.ArgumentParser(prog="pvcloth", description="Mass-spring cloth with PyVista.")
    parser.add_argument("--version", action="version", version=f"pvcloth {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    run = sub.add_parser(
        "run",
        help="open the interactive window: drag the cloth with the mouse",
        description="Animate a scene in a window; press on the cloth to drag a point "
        "(the keys are listed in the window; q quits). Needs a display (on a machine without one: "
        "xvfb-run -a pvcloth run SCENE).",
    )
    _add_overrides(run)
    run.add_argument("--fps", type=float, default=30.0, help="frames per second (default 30)")
    run.add_argument("--size", default="1024x768", help="window WIDTHxHEIGHT (default 1024x768)")
    run.set_defaults(func=cmd_run)

    info = sub.add_parser("info", help="print the model a scene builds")
    _add_overrides(info)
    info.set_defaults(func=cmd_info)

    simulate = sub.add_parser("simulate", help="run a scene without drawing and print a summary")
    _add_overrides(simulate)
    simulate.add_argument("--seconds", type=float, default=2.0, help="simulated time (default 2)")
    simulate.add_argument("--fps", type=float, default=30.0, help="frames per second (default 30)")
    simulate.add_argument("--quiet", action="store_true", help="no progress bar")
    simulate.set_defaults(func=cmd_simulate)

    render = sub.add_parser("render", help="write a GIF, MP4 or PNG off-screen")
    _add_overrides(render)
    render.add_argument("-o", "--output", required=True, help="OUT.gif, OUT.mp4 or OUT.png")
    render.add_argument("--frames", type=int, default=90, help="frames (default 90)")
    render.add_argument("--fps", type=float, default=30.0, help="frames per second (default 30)")
    render.add_argument("--size", default="640x480", help="WIDTHxHEIGHT (default 640x480)")
    _add_colors(render)
    render.add_argument("--quiet", action="store_true", help="no progress bar")
    render.set_defaults(func=cmd_render)

    compare = sub.add_parser(
        "compare",
        help="the same scene under several integrators, side by side in one movie",
        description="One panel per integrator under one camera, each labelled with its step, "
        "the wall time it takes per simulated second and its RMS distance from a fine RK4 "
        "reference run alongside.",
    )
    _add_overrides(compare, one_integrator=False)
    compare.add_argument(
        "--integrators",
        required=True,
        metavar="A,B,...",
        help="comma-separated, one panel each, e.g. symplectic_euler,rk4,fast_mass_spring "
        "(NAME+lbfgs: with solver.accelerator = 'lbfgs', e.g. fast_bdf2,fast_bdf2+lbfgs)",
    )
    compare.add_argument(
        "--dts",
        metavar="DT,...",
        help="each panel's step in seconds (auto = the automatic step; 1/60 allowed), "
        "one for all or one per integrator",
    )
    compare.add_argument("-o", "--output", required=True, help="OUT.gif, OUT.mp4 or OUT.png")
    compare.add_argument("--frames", type=int, default=90, help="frames (default 90)")
    compare.add_argument("--fps", type=float, default=30.0, help="frames per second (default 30)")
    compare.add_argument("--size", help="WIDTHxHEIGHT of the whole frame (default 480x360 a panel)")
    compare.add_argument(
        "--color", metavar="FIELD", help="colour every cloth by a field (as for render)"
    )
    compare.add_argument("--quiet", action="store_true", help="no progress bar")
    compare.set_defaults(func=cmd_compare)

    exp = sub.add_parser(
        "export",
        help="write a time series for ParaView (.pvd, .xdmf) or Blender (.pc2 point cache "
        "with its .obj, or .obj frames)",
    )
    _add_overrides(exp)
    exp.add_argument(
        "-o",
        "--output",
        required=True,
        help="OUT.pvd, OUT.xdmf, OUT.pc2 (writes OUT.obj beside it) or OUT.obj",
    )
    exp.add_argument("--frames", type=int, default=60, help="frames (default 60)")
    exp.add_argument("--fps", type=float, default=30.0, help="frames per second (default 30)")
    exp.add_argument("--quiet", action="store_true", help="no progress bar")
    exp.set_defaults(func=cmd_export)

    trade = sub.add_parser("tradeoff", help="error vs wall time for every integrator and step")
    trade.add_argument("scene", help="scene file (TOML)")
    trade.add_argument("-o", "--output", required=True, help="folder for tradeoff.csv/.png")
    trade.add_argument("--duration", type=float, default=0.25, help="simulated s per run")
    trade.add_argument("--integrators", help="comma-separated names (default: all)")
    trade.add_argument("--steps", help="comma-separated time steps in s (default: a range)")
    trade.add_argument(
        "--tolerances",
        help="comma-separated tolerances (m) for adaptive runs of the methods that measure their "
        "error, or 'none' (default: 1e-1,1e-2 for first-order methods, 1e-2 to 1e-5 for rk23)",
    )
    trade.add_argument("--resolution", type=int, help="points per side instead of the scene's")
    trade.add_argument("--quiet", action="store_true", help="no progress bar")
    trade.set_defaults(func=cmd_tradeoff)

    sweep = sub.add_parser(
        "sweep",
        help="stability and accuracy over a product of settings, on Dask",
        description="Each combination of --set values is a short simulation run on Dask; "
        "rows go to OUT/sweep.csv as they finish (a rerun skips finished rows).",
    )
    sweep.add_argument("scene", help="scene file (TOML)")
    sweep.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUES",
        help="a scene key and its values: a,b,c or START:STOP:Nlin or START:STOP:Nlog "
        "(repeat for more keys), e.g. --set solver.dt=1e-4:1e-2:8log",
    )
    sweep.add_argument("-o", "--output", required=True, help="folder for sweep.csv/.png")
    sweep.add_argument("--duration", type=float, default=0.25, help="simulated s per run")
    sweep.add_argument("--scheduler", help="address of a running Dask scheduler")
    sweep.add_argument("--workers", type=int, help="local workers (default: one per core)")
    sweep.add_argument("--axes", help="two swept keys for the stability map (KEY1,KEY2)")
    sweep.add_argument("--quiet", action="store_true", help="no progress bar")
    sweep.set_defaults(func=cmd_sweep)
    return parser


#: Exit codes of a run stopped by Ctrl-C (SIGINT) and by SIGTERM, as a shell gives.
EXIT_INTERRUPTED, EXIT_TERMINATED = 130, 143


def _interruption(error: BaseException) -> BaseException | None:
    """The KeyboardInterrupt (or Terminated) behind an error, if any."""
    while error is not None:
        if isinstance(error, KeyboardInterrupt):
            return error
        error = error.__cause__
    return None


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``pvcloth`` console command.

    Exit codes: 0 done, 2 pvcloth's own error (a message, no traceback),
    130 interrupted by Ctrl-C, 143 stopped by SIGTERM; what an interrupted
    command had written stays valid and its message says what was kept."""
    args = build_parser().parse_args(argv)
    if args.command in SIMULATING:
        from pvcloth.compilation import watch_compilation

        watch_compilation()  # says so when the first run compiles the kernels
    try:
        with handled():
            args.func(args)
    except (PvclothError, KeyboardInterrupt) as error:
        interruption = _interruption(error)
        if interruption is None:
            print(f"pvcloth: error: {error}", file=sys.stderr)
            return 2
        what = "terminated" if isinstance(interruption, Terminated) else "interrupted"
        detail = f": {error}" if isinstance(error, PvclothError) else ""
        print(f"pvcloth: {what}{detail}", file=sys.stderr)
        return EXIT_TERMINATED if isinstance(interruption, Terminated) else EXIT_INTERRUPTED
    return 0


if __name__ == "__main__":
    sys.exit(main())
