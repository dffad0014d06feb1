"""The docs site: generated pages in step with the docstrings, an animated page per env, no link out of the
repository, a strict mkdocs build, and the built pages in a real browser (headless Chromium, where installed)."""

from __future__ import annotations

import functools
import http.server
import importlib.util
import os
import re
import shutil
import socket
import subprocess
import sys
import threading
import urllib.parse
import warnings
from html import unescape
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

ROOT = Path(__file__).resolve().parents[1]
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def load(name, path):
    """The module at path, imported under name (docs/ and examples/ are no packages)."""
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def site_module():
    return load("docs_site", ROOT / "docs" / "site.py")


def test_the_generated_pages_are_what_the_docstrings_make():
    """Env pages, the generated physics pages, the README's gallery and the home page: regenerate with
    `python docs/site.py` after changing a docstring."""
    assert site_module().stale_pages() == []


def test_every_registered_env_has_a_page_with_its_animation():
    """At least 400 px wide, as Gymnasium's docs' animations are: their labels read."""
    site = site_module()
    assert site.ANIMATION_WIDTH >= 400
    for env_id in site.env_ids():
        name = site.name(env_id)
        page = (ROOT / "docs" / "envs" / f"{name}.md").read_text()
        assert f"]({name}.gif)" in page and f"`{env_id}`" in page
        gif = Image.open(ROOT / "docs" / "envs" / f"{name}.gif")
        assert gif.n_frames >= 20 and gif.width == site.ANIMATION_WIDTH, name
        assert (ROOT / "docs" / "envs" / f"{name}.gif").stat().st_size < 400_000, name


def test_no_table_of_the_pages_has_an_empty_header_row():
    """A Markdown table's header row (the line above its |---| line) names something in at least one cell: an env
    page's summary table had a header row of empty cells above its rows."""
    empty = []
    for path in markdown_files():
        lines = path.read_text().splitlines()
        for above, line in zip(lines, lines[1:]):
            if re.fullmatch(r"\|(\s*:?-+:?\s*\|)+", line) and not above.replace("|", "").strip():
                empty.append(f"{path.relative_to(ROOT)}: {above!r}")
    assert not empty, empty


def markdown_files():
    return [ROOT / "README.md", ROOT / "mkdocs.yml", *sorted((ROOT / "docs").rglob("*.md"))]


def test_no_link_points_outside_the_repository():
    """No URL at all, and every relative link (Markdown or HTML) resolves to a file inside the repository."""
    outside, missing = [], []
    for path in markdown_files():
        text = path.read_text()
        outside += [f"{path.relative_to(ROOT)}: {url}" for url in re.findall(r"\b(?:https?|ftp)://\S+", text)]
        targets = re.findall(r"\]\(([^)\s]+)\)", text) + re.findall(r'\bsrc="([^"]+)"', text)
        for target in targets:
            file = target.split("#", 1)[0]
            if not file:
                continue
            resolved = (path.parent / file).resolve()
            if not resolved.is_relative_to(ROOT):
                outside.append(f"{path.relative_to(ROOT)}: {target}")
            elif not resolved.exists():
                missing.append(f"{path.relative_to(ROOT)}: {target}")
    assert not outside, outside
    assert not missing, missing


@pytest.fixture(scope="module")
def built_site(tmp_path_factory):
    """The site from `mkdocs build --strict`: mkdocs.yml's `validation` makes each link mkdocs cannot resolve (a
    missing page, an absolute path, a folder such as `precision/`) a warning, which --strict turns into a failure."""
    folder = tmp_path_factory.mktemp("site")
    command = [sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(folder)]  # -q would hide the warnings
    build = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, env=os.environ | {"NO_MKDOCS_2_WARNING": "1"})
    if build.returncode != 0:
        pytest.fail(f"mkdocs build --strict failed:\n{build.stderr}")
    return folder


def internal_links(html: str) -> list[str]:
    """The paths of a page's href and src attributes that stay on the site (no scheme, no host, not only a #)."""
    urls = (urllib.parse.urlsplit(url) for url in re.findall(r'\b(?:href|src)="([^"]*)"', html))
    return [urllib.parse.unquote(url.path) for url in urls if url.path and not url.scheme and not url.netloc]


def test_every_internal_link_of_the_built_site_names_a_file(built_site):
    """A link mkdocs does not recognise is left as written; in the built site it must still name a file (a folder
    only where it holds an index.html, since a static server lists no folder)."""
    broken = []
    for page in sorted(built_site.rglob("*.html")):
        for path in internal_links(page.read_text()):
            target = (built_site / path.lstrip("/")) if path.startswith("/") else page.parent / path
            if not (target.is_file() or (target / "index.html").is_file()):
                broken.append(f"{page.relative_to(built_site)}: {path}")
    assert not broken, broken


def test_the_site_builds_strictly_with_a_page_per_env(built_site):
    """Each env's page, linked from the nav with its physics page (mkdocs.yml's wildcards, expanded by docs/nav.py)."""
    site = site_module()
    nav = (built_site / "index.html").read_text()
    for env_id in site.env_ids():
        page = built_site / "envs" / site.name(env_id) / "index.html"
        assert page.is_file() and f"{site.name(env_id)}.gif" in page.read_text()
        physics = site.spec(env_id).physics.removesuffix(".md")
        assert f'href="envs/{site.name(env_id)}/"' in nav and f'href="physics/{physics}/"' in nav, env_id
    assert (built_site / "envs" / "Swing-v0.gif").is_file()


@pytest.fixture(scope="module")
def served(built_site):
    """The built site on a free localhost port."""
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(built_site))
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    server = http.server.ThreadingHTTPServer(("127.0.0.1", port), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    yield f"http://127.0.0.1:{port}"
    server.shutdown()


def chromium_flags(tmp_path: Path) -> list[str]:
    """Headless Chromium with a fresh profile, reaching out to nothing."""
    return ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
            "--disable-background-networking", "--disable-component-update", "--disable-sync",
            f"--user-data-dir={tmp_path / 'profile'}"]  # fmt: skip


@pytest.mark.skipif(CHROMIUM is None, reason="Chromium is not installed (.ci/run installs Debian's package)")
@pytest.mark.parametrize("page", ["", "envs/Swing-v0/"])
def test_chromium_renders_the_home_page_and_an_env_page(served, page, tmp_path):
    """Headless Chromium loads the page (a screenshot that is not blank) and the page's animation is served."""
    import urllib.request

    shot = tmp_path / "page.png"
    flags = [*chromium_flags(tmp_path), "--window-size=1200,900", f"--screenshot={shot}"]
    subprocess.run([CHROMIUM, *flags, f"{served}/{page}"], check=True, capture_output=True, timeout=120)
    pixels = np.asarray(Image.open(shot).convert("RGB"))
    assert pixels.shape[:2] == (900, 1200) and len(np.unique(pixels.reshape(-1, 3), axis=0)) > 50
    html = urllib.request.urlopen(f"{served}/{page}").read().decode()
    gif = re.search(r'src="([^"]+\.gif)"', html).group(1)
    response = urllib.request.urlopen(f"{served}/{page}{gif}")
    assert response.status == 200 and response.headers["Content-Type"] == "image/gif"


LAYOUT_PAGES = ["", "envs/ActiveConstraint-v0/", "guides/own-system/"]
LAYOUT_PROBE = """<!doctype html><pre id="result"></pre><script>
// Each page in a 1200 px frame, after the theme's scripts have added the copy buttons: for each code block, how far
// its lines run past its right edge and how many of its line boxes lie under its copy button; for each image in a
// table, its width attribute and its drawn width; for each code span in a table, how many lines it takes.
const pages = %s, found = {};
for (const page of pages) {
  const frame = document.body.appendChild(Object.assign(document.createElement("iframe"), {width: 1200, height: 900}));
  frame.onload = () => setTimeout(() => {
    const d = frame.contentDocument;
    const blocks = [...d.querySelectorAll("pre > code")].map(code => {
      const button = code.parentElement.querySelector(".md-code__button").getBoundingClientRect(), range = d.createRange();
      range.selectNodeContents(code);
      const covered = [...range.getClientRects()].filter(r => r.width > 0 && r.right > button.left
        && r.left < button.right && r.bottom > button.top && r.top < button.bottom);
      return {start: code.textContent.slice(0, 40), overflow: code.scrollWidth - code.clientWidth, covered: covered.length};
    });
    const images = [...d.querySelectorAll("table img")].map(img => [+img.getAttribute("width"), img.width]);
    const spans = [...d.querySelectorAll("td code")].map(code => [code.textContent, code.getClientRects().length]);
    found[page] = {blocks, images, spans};
    if (Object.keys(found).length === pages.length) document.getElementById("result").textContent = JSON.stringify(found);
  }, 500);
  frame.src = "/" + page;
}
</script>"""


@pytest.mark.skipif(CHROMIUM is None, reason="Chromium is not installed (.ci/run installs Debian's package)")
def test_chromium_lays_out_code_thumbnails_and_class_names_readably(served, built_site, tmp_path):
    """At 1200 px, in the home page, an env page and the guide with the longest command: no code block runs off its
    right edge and no copy button covers code; the gallery's thumbnails are drawn at their width, THUMBNAIL_WIDTH;
    no code span in a table (a class name) breaks across lines."""
    import json

    (built_site / "layout-probe.html").write_text(LAYOUT_PROBE % json.dumps(LAYOUT_PAGES))
    flags = [*chromium_flags(tmp_path), "--virtual-time-budget=10000", "--dump-dom"]
    dom = subprocess.run([CHROMIUM, *flags, f"{served}/layout-probe.html"], check=True, capture_output=True, text=True,
                         timeout=120).stdout  # fmt: skip
    found = json.loads(unescape(re.search(r'<pre id="result">(.*?)</pre>', dom, re.DOTALL).group(1)))
    assert found.keys() == set(LAYOUT_PAGES) and found[""]["images"] and found["guides/own-system/"]["blocks"]
    width, problems = site_module().THUMBNAIL_WIDTH, []  # the gallery's width: a thumbnail not squeezed by the table
    for page, layout in found.items():
        problems += [(page, block) for block in layout["blocks"] if block["overflow"] > 0 or block["covered"]]
        problems += [(page, "image", image) for image in layout["images"] if image != [width, width]]
        problems += [(page, "code span", span) for span in layout["spans"] if span[1] != 1]
    assert not problems, problems


def guide_example():
    """examples/my_robot.py, the module that docs/guides/own-system.md trains on."""
    return load("my_robot", ROOT / "examples" / "my_robot.py")


def test_the_own_system_guide_trains_on_its_example_module():
    """The guide's command names examples/my_robot.py, and the code it shows is that file's."""
    guide = (ROOT / "docs" / "guides" / "own-system.md").read_text()
    assert "python train.py --env connenv/ActiveConstraint-v0 --env-kwargs examples.my_robot:env_kwargs" in guide
    source = (ROOT / "examples" / "my_robot.py").read_text()
    shown = re.search(r"`examples/my_robot.py`, here without its imports:\n\n```python\n(.*?)```", guide, re.DOTALL).group(1)
    assert shown in source


def test_the_guide_example_makes_a_valid_env_with_a_task_that_a_conserved_quantity_solves():
    """The example's kwargs make an env that Gymnasium's checker passes. At rest θ + J u/(I + J) is conserved, so the
    rotor commanded to u* = (θ₀ − TARGET)(I + J)/J turns the body to TARGET: the episode ends a success with rewards
    rising toward 0; under a random policy the rewards vary (the guide's system without a task had reward 0 always)."""
    import gymnasium as gym
    from gymnasium.utils.env_checker import check_env

    import connenv  # noqa: F401  (registers the envs)

    example = guide_example()
    env = gym.make("connenv/ActiveConstraint-v0", **example.env_kwargs())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the builder's unbounded observation Box is by design
        check_env(env.unwrapped)
    obs, _ = env.reset(seed=3)
    u_star = (obs[0] - example.TARGET) * (example.I + example.J) / example.J
    rewards, done = [], False
    while not done:
        obs, reward, terminated, truncated, info = env.step(np.array([u_star / np.pi], np.float32))
        rewards.append(reward)
        done = terminated or truncated
    assert terminated and info["is_success"] and abs(info["state"]["q"][0] - example.TARGET) < example.TOLERANCE
    assert np.all(np.diff(rewards) > 0) and len(rewards) > 1
    env.action_space.seed(0)
    env.reset(seed=4)
    random_rewards = [env.step(env.action_space.sample())[1] for _ in range(50)]
    assert np.ptp(random_rewards) > 0.01


def test_every_page_is_in_the_nav():
    """mkdocs.yml's nav (its wildcards expanded by docs/nav.py) names every page under docs/: a page left out is
    only an INFO line of mkdocs build, and the README links docs/baselines/score.md."""
    import importlib.util

    import yaml

    hook = importlib.util.spec_from_file_location("docs_nav", ROOT / "docs" / "nav.py")
    nav = importlib.util.module_from_spec(hook)
    hook.loader.exec_module(nav)
    config = yaml.safe_load((ROOT / "mkdocs.yml").read_text())
    docs = ROOT / config["docs_dir"]
    listed = set(nav.named(nav.on_config({"nav": config["nav"], "docs_dir": str(docs)})["nav"]))
    pages = {path.relative_to(docs).as_posix() for path in docs.rglob("*.md")}
    assert not pages - listed, f"not in mkdocs.yml's nav: {sorted(pages - listed)}"
