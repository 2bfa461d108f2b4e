"""The documentation builds with warnings as errors (a broken link, a
missing page, a docstring Sphinx cannot read, an unresolved reference to
the public API all fail), its command line page is generated from the
parser, its API page lists ``isoflow.__all__``, and its gallery shows a
picture of every example. Skipped, with the reason, when Sphinx and its
extensions are not installed (``pip install -e '.[docs]'``)."""

from __future__ import annotations

import argparse
import re
from html.parser import HTMLParser

from docs_site import example_names, script_output_pictures

import isoflow
from isoflow.cli.main import build_parser


class _Text(HTMLParser):
    def __init__(self):
        super().__init__()
        self.parts, self.skip = [], 0

    def handle_starttag(self, tag, attrs):
        self.skip += tag in ("script", "style")

    def handle_endtag(self, tag):
        self.skip -= tag in ("script", "style")

    def handle_data(self, data):
        if not self.skip:
            self.parts.append(data)


def text_of(page) -> str:
    """A page's text as a reader sees it, whitespace collapsed."""
    parser = _Text()
    parser.feed(page.read_text())
    return " ".join(" ".join(parser.parts).split())


def test_the_site_builds_without_a_warning(site):
    assert site.returncode == 0 and not site.warnings(), "\n".join(site.warnings()) or site.log[-3000:]
    for page in ("index", "getting-started", "cli", "api", "mathematics", "formats", "voxelisation",
                 "large-volumes", "flow", "ndim", "performance", "architecture", "changelog", "auto_examples/index"):
        assert (site.html / f"{page}.html").is_file(), page


def test_the_command_line_page_is_the_parser(site):
    """Every command, option and choice of build_parser() is on the page."""
    page = text_of(site.html / "cli.html")
    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices
    assert set(commands) == {"info", "surface", "voxelize", "genus", "flow", "completion"}
    for name, sub in commands.items():
        assert f"isoflow {name} " in page, name
        for action in sub._actions:
            if isinstance(action, argparse._HelpAction):  # -h is every command's, not listed
                continue
            for option in action.option_strings:
                assert option in page, (name, option)
            assert action.help is None or action.help == argparse.SUPPRESS or \
                " ".join(action.help.split()[:4]) in page, (name, action.dest)


def test_the_api_page_is_the_public_api(site):
    page = text_of(site.html / "api.html")
    for name in isoflow.__all__:
        assert name in page, name
        if name != "data":  # the subpackage: a section with a page per function
            assert (site.html / "generated" / f"isoflow.{name}.html").is_file(), name
    for name in isoflow.data.__all__:
        assert (site.html / "generated" / f"isoflow.data.{name}.html").is_file(), name


def test_every_reference_to_the_public_api_links_to_its_page(site):
    """Docstrings name public functions by the modules that define them
    (``:func:`~isoflow.digital.topology.euler_characteristic```), which have
    no page: the build let them pass (conf.py's nitpick_ignore_regex) and
    showed them as code without a link, 20 of them, on the API page too."""
    public = {*isoflow.__all__, *isoflow.data.__all__}
    unlinked = []
    for page in site.html.rglob("*.html"):
        for link, code in re.findall(r'(<a [^>]*>)?<code class="xref py[^"]*"[^>]*>(.*?)</code>', page.read_text(), re.S):
            name = re.sub(r"<[^>]+>", "", code).removesuffix("()").rpartition(".")[2]
            if not link and name in public:
                unlinked.append(f"{page.relative_to(site.html)}: {name}")
    assert not unlinked, unlinked


def test_a_class_page_documents_the_class_s_members(site):
    """The class template's ``:members:`` was overridden by conf.py's
    ``autodoc_default_options = {"members": False}``: every class page held
    its docstring alone (no ``DigitalObject.from_points``, no
    ``QuadMesh.components``, no ``Report.from_dict``, which cli.md names).
    ``to_dict``, the command line's JSON, is a member of every result."""
    members = {"DigitalObject": ["from_points", "cropped"], "QuadMesh": ["components"], "LabelImage": [],
               "Report": ["from_dict", "to_dict"], "FlowResult": ["from_dict", "to_dict"],
               "GenusVerdict": ["from_dict", "to_dict"]}
    for name, wanted in members.items():
        page = (site.html / "generated" / f"isoflow.{name}.html").read_text()
        documented = set(re.findall(rf'id="isoflow\.{name}\.(\w+)"', page))
        assert documented >= set(wanted) and documented, (name, sorted(documented))
        assert not documented & {"keys", "items", "values", "get"}, (name, "Mapping's methods are not isoflow's")


def test_a_constant_s_page_says_what_it_holds(site):
    """CLASS_LABELS's page gave the docstring of its type, a tuple's
    ("Built-in immutable sequence"): autodoc looks for the constant's
    comment in isoflow/__init__.py, which only loads the name."""
    text = text_of(site.html / "generated" / "isoflow.CLASS_LABELS.html")
    assert "Built-in immutable sequence" not in text and "label of class gamma + 4" in text


def test_the_gallery_shows_every_example_with_its_picture(site):
    names = example_names()
    assert len(names) >= 6
    index = (site.html / "auto_examples" / "index.html").read_text()
    for name in names:
        assert f"{name}.html" in index, name
        pictures = script_output_pictures(site, name)
        assert pictures, f"{name}: the gallery shows no picture"
        for src in pictures:
            assert (site.html / "auto_examples" / src).resolve().is_file(), (name, src)
