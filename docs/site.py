"""The docs site's generated part: a page per registered env from its class docstring, with an animation of the env
under its analytic controller, as Gymnasium's docs are made.

    python docs/site.py                 # write docs/envs/{name}.md, the generated physics pages, README's gallery
    python docs/site.py --animations    # also record docs/envs/{name}.gif (about a minute)
    python docs/site.py --maps          # also draw docs/envs/{name}-curvature.png (python -m connenv.geometry)
    python docs/site.py --check         # exit 1 naming the pages that differ from what the docstrings make

A subclass's docstring (RollingBallGoal-v0's, KapitzaSwingUp-v0's) gives what differs; the sections it leaves out
are its base class's. The animations are recorded with imageio from ``render_mode="rgb_array"``: at the canvas's own
ANIMATION_WIDTH pixels (not resampled, so that their labels read and they compress; the README's gallery shows them
THUMBNAIL_WIDTH wide), about ANIMATION_FPS frames a second, at most MAX_FRAMES frames (and MIN_FRAMES over
MIN_SECONDS for a short episode, in slow motion), under the env's first analytic controller (agents/controllers.py),
or a periodic shape change for the two builders, which have none.
"""

from __future__ import annotations

import argparse
import importlib
import inspect
import re
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np

import connenv
from connenv.envs.spec import registry, spec
from connenv.rendering import SIZE

DOCS = Path(__file__).resolve().parent
PAGES = DOCS / "envs"
SECTIONS = ("Description", "Action Space", "Observation Space", "Rewards", "Starting State", "Episode End", "Arguments")
ANIMATION_WIDTH, THUMBNAIL_WIDTH = SIZE, 200
ANIMATION_FPS, MAX_FRAMES, MIN_FRAMES, MIN_SECONDS = 12, 90, 30, 3.0
VERSION_HISTORY = "- v0: the first version, in connenv 0.1.0."
STEPPERS = """## Scales, steppers and errors

An action is taken in float64 (a float64 action at its own precision) and clipped into the action space, unless the
Action Space says otherwise. A wrong shape or a non-finite value of an action, and an unknown key or a value out of
its range of a reset option or a kwarg, is a ValueError naming it, the value and the valid range.

A physical scale (a length, mass, inertia, density, g, a speed or rate bound, a tolerance) lies within a factor 1e6
of its default either way, or down to 0 where 0 has a meaning, unless the Arguments table bounds it otherwise
(`connenv.core.validation.check_scale`): from a toy to a ship, while the energies, momenta, observation bounds and
rewards an env forms of its scales stay inside float64 and the float32 observation.

`integrator` picks the stepper (`connenv.core.integrators.make_stepper`; the Arguments table lists the env's). The
fixed-step methods "euler", "semi_implicit_euler" (on a state (q, p) only), "rk4", "rk8", "rk8_energy" and "gauss6"
take `substeps`, an integer in [1, 1000] per control segment (a part of the step where the controls move
uniformly); "rk8_energy" also takes `atol`, the energy error per segment past which it doubles them. Scipy's
"dop853", "rk45", "lsoda" and "radau" take `rtol` and `atol`, and so does "exact" for the segments it has no closed
form for. "magnus", the Lie-group step, takes `atol`, its error bound per segment.

A stepper that diverges raises `connenv.core.StepperError`, never a NaN observation; the message names the stepper,
the env, the time, dt and the physical parameters. Diverging is a non-finite state, an adaptive stepper that cannot
meet its tolerance, or the invariant the env checks every step past its bound ("Diverged" above, where it has one).
An energy error is the change of the energy over the segments where the flow conserves it, summed since reset: the
work the controls do is exact and not counted.
"""
"""The generic section of every env page, after its Arguments; `steppers_section` ends it with the env's chart."""
GALLERY_MARKS = ("<!-- gallery: python docs/site.py -->", "<!-- end of gallery -->")
GENERATED_PHYSICS = {
    "framework.md": (
        "Active constraints: Bressan's framework",
        (
            "A controller that assigns some coordinates of a mechanical system directly — a radius, a height, a pivot's "
            "position — steers the others through the kinetic energy's coupling. Bressan's Hamiltonian gives the free "
            "coordinates' motion for any control path, and how the control's velocity enters it sorts systems into "
            "classes: those a jump of the control moves by a fixed amount, and those it does not."
        ),
        ["connenv.core.mechanics", "connenv.core.mechanics:JumpClass", "connenv.core.lagrangian"],
        ["tests/test_core.py", "tests/test_active_constraint.py"],
    ),
    "connections.md": (
        "Mechanical connections and holonomy",
        (
            "When a conserved momentum is zero, a body's motion is slaved to its shape: a connection A turns each shape "
            "velocity into a group velocity, and a closed loop of shapes moves the body by the loop's holonomy — the "
            "curvature of A integrated over the area the loop encloses, whatever the speed of the loop."
        ),
        ["connenv.core.lie", "connenv.envs.connection", "connenv.geometry"],
        ["tests/test_connection.py", "tests/test_geometry.py"],
    ),
    "swing.md": (
        "The swing",
        "A child pumps a swing by standing and squatting: the radius is the assigned coordinate.",
        ["connenv.systems.swing", "connenv.systems.swing:Swing.exact_flow"],
        ["tests/test_swing_physics.py"],
    ),
    "skier.md": (
        "The skier",
        "A skier on an undulating trail pumps by raising and lowering the barycentre along the trail's normal.",
        ["connenv.systems.skier", "connenv.systems.trails"],
        ["tests/test_skier_physics.py"],
    ),
    "rolling-ball.md": (
        "The rolling ball",
        (
            "A ball rolled on a plane without slipping or turning about the vertical is reoriented by the loops its "
            "contact point draws: the holonomy of the rolling distribution."
        ),
        ["connenv.systems.rolling_ball"],
        ["tests/test_rolling_ball_physics.py"],
    ),
    "kozlov-shell.md": (
        "Kozlov's shell in an ideal fluid",
        (
            "An elliptic shell swims through an ideal fluid by moving a mass inside it; the fluid acts only through "
            "its added masses, in closed form."
        ),
        ["connenv.systems.kozlov_shell"],
        ["tests/test_kozlov_shell_physics.py"],
    ),
    "kapitza.md": (
        "Kapitza's pendulum",
        "A pendulum whose pivot is assigned: fast vibration of the pivot holds it upright.",
        ["connenv.systems.kapitza", "connenv.systems.kapitza:KapitzaPendulum.exact_segment"],
        ["tests/test_kapitza_physics.py"],
    ),
}
"""The physics pages written from the modules' docstrings (title, lead, modules, the test files that check them);
the others under docs/physics/ are written by hand."""


def env_ids() -> list[str]:
    return sorted(registry)


def name(env_id: str) -> str:
    return env_id.split("/")[1]


def env_class(env_id: str) -> type:
    module, attribute = gym.spec(env_id).entry_point.split(":")
    return getattr(importlib.import_module(module), attribute)


def sections(cls: type) -> dict[str, str]:
    """The '## ' sections of a class's docstring, each with its text, in order; a heading that joins several
    ('Action Space, Observation Space, Arguments') stands for each."""
    text = inspect.cleandoc(cls.__dict__.get("__doc__") or "")
    found = {}
    for part in re.split(r"^## ", text, flags=re.MULTILINE)[1:]:
        heading, _, body = part.partition("\n")
        for title in heading.split(", "):
            found[title.strip()] = body.strip()
    return found


def merged_sections(cls: type) -> dict[str, str]:
    """The class's sections, with those it leaves out taken from its base classes (nearest first)."""
    merged = {}
    for base in reversed(cls.__mro__):
        merged.update(sections(base))
    ordered = [title for title in SECTIONS if title in merged] + [t for t in merged if t not in SECTIONS]
    return {title: merged[title] for title in ordered}


def controller_name(env_id: str) -> str:
    from agents.controllers import CONTROLLERS

    known = CONTROLLERS.get(env_id)
    return f"`{next(iter(known))}`" if known else "none (a builder): the animation is a periodic shape change"


def make(env_id: str, **kwargs):
    return gym.make(env_id, **spec(env_id).make_kwargs(), **kwargs)


def page(env_id: str) -> str:
    """The env's page: summary table, animation, the docstring's sections, physics link, version history."""
    cls, env = env_class(env_id), make(env_id)
    summary = inspect.getmodule(cls).__doc__.strip().splitlines()[0]
    rows = [
        ("id", f"`{env_id}`"),
        ("class", f"`{cls.__module__}.{cls.__qualname__}`"),
        ("action space", f"`{env.action_space}`"),
        ("observation space", f"`{env.observation_space}`".replace("\n", " ")),
        ("time limit", f"{gym.spec(env_id).max_episode_steps} steps"),
        *([("registered with", f"`{gym.spec(env_id).kwargs}`")] if gym.spec(env_id).kwargs else []),
        ("analytic controller", controller_name(env_id)),
        ("physics", f"[{spec(env_id).physics.removesuffix('.md')}](../physics/{spec(env_id).physics})"),
    ]
    env.close()
    lines = [f"# {name(env_id)}", "", summary, "", f"![{name(env_id)} under its controller]({name(env_id)}.gif)", ""]
    header, *rest = (f"| {key} | {value} |" for key, value in rows)  # the id row heads the table: no empty header row
    lines += [header, "|---|---|", *rest, ""]
    for title, body in merged_sections(cls).items():
        lines += [f"## {title}", "", body, ""]
        if title == "Description":
            lines += map_section(env_id)
        if title == "Arguments":
            lines += model_section(env_id) + steppers_section(env_id)
    lines += reference_results(env_id)
    if "Version History" not in merged_sections(cls):  # a class with later versions has its own
        lines += ["## Version History", "", VERSION_HISTORY, ""]
    return "\n".join(lines)


def model_section(env_id: str) -> list[str]:
    """The env's physical parameters as an episode's context, and its model's state vector (connenv.core.model)."""
    from connenv.core.context import physical_params

    env = make(env_id).unwrapped
    declared, model = physical_params(env), env.model
    lines = ["## Parameters and model", ""]
    if declared:
        lines += [
            "The physical parameters, which `reset(options={\"params\": {...}})` sets for an episode and "
            "`gym.make(id, randomize={name: (low, high)})` draws per episode (uniform, or log-uniform for a scale drawn above 0), "
            "within their ranges ([the model guide](../guides/model.md)):", "",
            "| parameter | value | range | draw |", "|---|---|---|---|",
            *(f"| `{n}` | {getattr(env.args, n)} {p.unit} | {p.span()} | "
              f"{'log-uniform' if p.kind == 'scale' else 'uniform'} |" for n, p in declared.items()), "",
        ]  # fmt: skip
    else:
        lines += ["No declared physical parameters: the system's are the user's.", ""]
    names = ", ".join(f"`{n}`" for n in model.state_names)
    lines += [f"`env.unwrapped.model` steps a state vector of {model.n} entries: {names}. `model.jacobians` "
              "differentiates the step by complex step, exact to rounding, with any of the env's steppers but "
              "\"lsoda\" and \"radau\" (which step rows one by one and take no complex numbers).", ""]
    traced = spec(env_id).jax
    if traced and spec(env_id).example:  # a builder: the user's functions trace, or make says what they need
        kwargs = ", ".join(f"`{k.__module__}.{k.__name__}()`" if callable(k) else f"`{k}`" for k in traced)
        lines += [f"**JAX:** `connenv.jax.make(\"{env_id}\", **make_kwargs)` gives this step as a pure JAX function "
                  "(jit, vmap, grad), the same code traced, where the user's functions take JAX arrays (else a "
                  "TypeError saying what they need); tests/test_jax.py checks it against the numpy step with "
                  f"{kwargs}. How it may differ: [the JAX guide](../guides/jax.md).", ""]
    elif traced:
        kwargs = ", ".join(f"`{k}`" if k else "the default make kwargs" for k in traced)
        lines += [f"**JAX:** `connenv.jax.make(\"{env_id}\")` gives this step as a pure JAX function (jit, vmap, "
                  f"grad), the same code traced; tests/test_jax.py checks it against the numpy step with {kwargs}. "
                  "How it may differ: [the JAX guide](../guides/jax.md).", ""]
    else:
        lines += ["**JAX:** no JAX version yet (`connenv.jax.make` refuses this id; [the JAX guide](../guides/jax.md)).",
                  ""]
    env.close()
    return lines


ONE_DIMENSIONAL = (
    "The shape space is 1-D: a loop of shapes encloses no area, so the connection is flat (F = 0), and a shape path "
    "that returns moves the body only by the times it winds (`connenv.geometry.loop_holonomy`, "
    "[the geometry of connections](../physics/connections.md))."
)


def curvature_map(env_id: str) -> Path:
    return PAGES / f"{name(env_id)}-curvature.png"


def draw_map(env_id: str) -> bool:
    """Draw the env's curvature map with its analytic gait (agents.curvature_map) where it has a connection on a 2-D
    shape space."""
    from agents import curvature_map as maps

    try:
        maps.draw(env_id, str(curvature_map(env_id)))
    except ValueError:  # no connection, or not a 2-D shape space: no map
        return False
    return True


def map_section(env_id: str) -> list[str]:
    """The curvature map with the analytic gait, where ``--maps`` drew one; a word where the shape space is 1-D."""
    from connenv import geometry

    if not curvature_map(env_id).is_file():
        try:
            one = geometry.local_connection(make(env_id)).low.size == 1
        except ValueError:  # no connection
            one = False
        return ["## Curvature map", "", ONE_DIMENSIONAL, ""] if one else []
    return [
        "## Curvature map", "",
        "The curvature F of the connection over the shape space, one panel per group direction that moves (colour; "
        "a small loop of area a, counterclockwise, moves the body by about −F a in that direction), the shape "
        "velocities −A that move it fastest (arrows), and the analytic controller's gait (black), drawn by "
        f"`python -m connenv.geometry {env_id}` ([the geometry of connections](../physics/connections.md)):", "",
        f"![curvature map of {name(env_id)}]({curvature_map(env_id).name})", "",
    ]  # fmt: skip


def steppers_section(env_id: str) -> list[str]:
    """STEPPERS, then where the env's steppers are compared: its section of docs/speed-accuracy.md and the command
    that measures it, where its spec's ``bench`` key has a work–precision chart (ActiveConstraint-v0's has none)."""
    key, guide = spec(env_id).bench, "[the speed–accuracy guide](../guides/speed-accuracy.md)"
    if key and (DOCS / "precision" / f"{key}_precision.csv").is_file():
        where = (f"Each stepper's errors and cost against the others are on [docs/speed-accuracy.md]"
                 f"(../speed-accuracy.md#{key}), which `python -m connenv.bench precision --env {key}` measures; "
                 f"{guide} says how, and over which ranges the tests check the defaults.")  # fmt: skip
    else:
        where = f"How steppers' errors and cost are measured, and over which ranges the tests check defaults: {guide}."
    return [STEPPERS, where, ""]


def reference_results(env_id: str) -> list[str]:
    """The env's section of the benchmark, from the files its commands wrote (docs/baselines/): the score on the
    unseen episodes, and where they were run, the behaviour clones of the diagnosis and the 10x budget curve."""
    import csv
    import json

    from agents import score

    unseen = json.loads((DOCS / "baselines" / "unseen.json").read_text())
    if env_id not in unseen["envs"]:
        return []
    lines = [
        "## Reference results", "",
        f"Every seed on the score's unseen episodes (reset with seeds {unseen['first_seed']} and up), from "
        "`python -m agents.baselines score` ([all envs](../baselines/score.md), "
        "[how they were trained](../guides/reference-results.md)):", "",
        *score.env_table({"envs": {env_id: unseen["envs"][env_id]}}), "",
    ]  # fmt: skip
    diagnosis = {entry["env"]: entry for entry in json.loads((DOCS / "baselines" / "diagnosis.json").read_text())}
    if env_id in diagnosis:
        clone = diagnosis[env_id]["clone_summary"]
        lines += [f"- Behaviour clones of the analytic controller into PPO's network (`python -m agents.imitate "
                  f"--diagnose`), on their own evaluation episodes: {100 * clone['success_mean']:.0f}% success "
                  f"[{100 * clone['success_ci'][0]:.0f}, {100 * clone['success_ci'][1]:.0f}]."]  # fmt: skip
    with (DOCS / "baselines" / "long.csv").open() as file:
        curve = [row for row in csv.DictReader(file) if row["env"] == env_id]
    if curve:
        best = max(float(row["success"]) for row in curve)
        lines += [f"- PPO at 10x the budget (one seed, `python -m agents.baselines collect --long`): "
                  f"{100 * float(curve[-1]['success']):.0f}% of its periodic evaluation episodes at "
                  f"{int(curve[-1]['timesteps']):,} steps, {100 * best:.0f}% at best."]  # fmt: skip
    return lines + ([""] if lines[-1] else [])


def tests_of(path: str) -> list[str]:
    """'- `test_name`: its docstring's first line' for each test function of a test file."""
    import ast

    tree = ast.parse((DOCS.parent / path).read_text())
    lines = []
    for node in tree.body:
        if isinstance(node, ast.FunctionDef) and node.name.startswith("test_"):
            doc = (ast.get_docstring(node) or "").split("\n\n")[0].replace("\n", " ")
            lines.append(f"- `{node.name}`" + (f": {doc}" if doc else ""))
    return lines


def docstring_of(target: str) -> str:
    """The docstring of a module, or of 'module:Qualified.name' in it."""
    module, _, qualname = target.partition(":")
    found = importlib.import_module(module)
    for part in qualname.split(".") if qualname else ():
        found = getattr(found, part)
    return found.__doc__


def physics_page(filename: str) -> str:
    """A physics page from its modules' docstrings and the names of the tests that check them."""
    title, lead, modules, tests = GENERATED_PHYSICS[filename]
    lines = [f"# {title}", "", lead, ""]
    for module in modules:
        lines += [f"## `{module}`", "", inspect.cleandoc(docstring_of(module)), ""]
    lines += ["## What the tests check", ""]
    for path in tests:
        lines += [f"`{path}`:", "", *tests_of(path), ""]
    envs = [f"[{name(e)}](../envs/{name(e)}.md)" for e in env_ids() if spec(e).physics == filename]
    return "\n".join(lines + ([f"Envs: {', '.join(envs)}.", ""] if envs else []))


def shape_size(space) -> str:
    """The size of a space: its shape's product, or the sizes of a Dict's parts."""
    if isinstance(space, gym.spaces.Dict):
        return " + ".join(f"{key} {shape_size(part)}" for key, part in space.spaces.items())
    return str(int(np.prod(space.shape)))


def gallery() -> str:
    """The README's table of every env: its animation shown THUMBNAIL_WIDTH wide, class, action and observation sizes,
    analytic controller."""
    from agents.controllers import CONTROLLERS

    lines = ["| | env | class | action | observation | analytic controller |", "|---|---|---|---|---|---|"]
    for env_id in env_ids():
        env, cls, short = make(env_id), env_class(env_id), name(env_id)
        controller = next(iter(CONTROLLERS[env_id])) if env_id in CONTROLLERS else "–"
        lines.append(
            f'| <img src="docs/envs/{short}.gif" width="{THUMBNAIL_WIDTH}"> | [{short}](docs/envs/{short}.md) '
            f"| `{cls.__name__}` "
            f"| {shape_size(env.action_space)} | {shape_size(env.observation_space)} | {controller} |"
        )
        env.close()
    return "\n".join(lines)


def readme_with_gallery(readme: str) -> str:
    """The README with its gallery (between GALLERY_MARKS) as the envs make it now."""
    start, end = GALLERY_MARKS
    before, rest = readme.split(start, 1)
    return before + start + "\n" + gallery() + "\n" + end + rest.split(end, 1)[1]


def expected_pages() -> dict[Path, str]:
    """Every generated page by path: the env pages, the generated physics pages, the README's gallery and the home
    page."""
    pages = {PAGES / f"{name(env_id)}.md": page(env_id) for env_id in env_ids()}
    pages.update((DOCS / "physics" / filename, physics_page(filename)) for filename in GENERATED_PHYSICS)
    readme = DOCS.parent / "README.md"
    pages[readme] = readme_with_gallery(readme.read_text())
    pages[DOCS / "index.md"] = home(pages[readme])
    return pages


def home(readme: str) -> str:
    """The site's home page: the README, its links made relative to docs/."""
    return readme.replace("](docs/", "](").replace('src="docs/', 'src="')


def write_pages() -> list[Path]:
    PAGES.mkdir(exist_ok=True)
    for path, text in expected_pages().items():
        path.write_text(text)
    return list(expected_pages())


def stale_pages() -> list[str]:
    """The generated pages that are missing or differ from what the docstrings make, and env pages of no registered
    env."""
    expected = {path: text for path, text in expected_pages().items()}
    present = {path: path.read_text() for path in [*PAGES.glob("*.md"), *expected] if path.is_file()}
    stale = (p for p in expected.keys() | present.keys() if expected.get(p) != present.get(p))
    return sorted(str(p.relative_to(DOCS.parent)) for p in stale)


def policy(env_id: str, env):
    """The env's first analytic controller as a function of the observation, or a periodic shape change."""
    from agents.controllers import CONTROLLERS, controller

    if env_id in CONTROLLERS:
        law, state = controller(env_id, env=env), None

        def act(observation):
            nonlocal state
            action, state = law.predict(observation, state=state, deterministic=True)
            return action

        return act
    clock = iter(range(10**9))
    return lambda observation: np.full(env.action_space.shape, np.sin(0.2 * next(clock)), np.float32)


def record(env_id: str, path: Path, seed: int = 0) -> int:
    """An episode under the env's controller as a GIF, at about ANIMATION_FPS frames of the env's time a second, in
    slow motion for an episode shorter than MIN_SECONDS; returns its frame count."""
    import imageio.v3 as iio

    env = make(env_id, render_mode="rgb_array")
    observation, _ = env.reset(seed=seed, options=spec(env_id).animation_start)
    fps = env.metadata["render_fps"]
    act, stride = policy(env_id, env.unwrapped), max(1, round(fps / ANIMATION_FPS))
    pictures, done = [], False
    while not done and len(pictures) < MAX_FRAMES * stride:
        pictures.append(env.render())
        observation, _, terminated, truncated, _ = env.step(act(observation))
        done = terminated or truncated
    pictures.append(env.render())
    env.close()
    stride = max(1, min(stride, len(pictures) // MIN_FRAMES))
    frames = pictures[::stride]
    duration = max(1000.0 * stride / fps, 1000.0 * MIN_SECONDS / len(frames))
    iio.imwrite(path, np.stack(frames), duration=duration, loop=0, plugin="pillow")
    return len(frames)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--check", action="store_true", help="compare the pages with the docstrings' instead")
    parser.add_argument("--animations", action="store_true", help="also record the animations")
    parser.add_argument("--maps", action="store_true", help="also draw the connection envs' curvature maps")
    args = parser.parse_args(argv)
    if args.check:
        stale = stale_pages()
        print(f"stale env pages: {stale}; regenerate with python docs/site.py" if stale else "env pages up to date")
        return 1 if stale else 0
    for path in write_pages():
        print(f"wrote {path.relative_to(DOCS.parent)}")
    for env_id in env_ids() if args.maps else ():
        if draw_map(env_id):
            print(f"wrote {curvature_map(env_id).relative_to(DOCS.parent)}")
    if args.maps:
        write_pages()  # the pages of the envs with a map show it
    for env_id in env_ids() if args.animations else ():
        gif = PAGES / f"{name(env_id)}.gif"
        frames = record(env_id, gif)
        print(f"wrote {gif.relative_to(DOCS.parent)}: {frames} frames, {gif.stat().st_size // 1024} kB")
    return 0


if __name__ == "__main__":
    assert connenv  # registers the envs
    sys.exit(main())
