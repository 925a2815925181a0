"""Reports as a reader sees them: pages in headless Chromium, PDFs rasterised by poppler.

A short virtual test is fitted, simulated and compared, and its report built in full
and with parts of its inputs missing; the campaign report over it too. Each HTML page
is loaded in Debian's ``chromium`` (no broken image, nothing wider than the window);
each PDF is rasterised by ``pdftoppm`` and read by ``pdftotext`` and ``pdfimages`` (its
pages, its sections and tables, one image per figure). The browser and poppler are
installed by the repository's CI set-up (``.ci/run``); without them those checks skip,
saying so.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from slipwave.bench.generate import BenchTest, simulate_test
from slipwave.campaign_report import campaign_summary, write_campaign_report
from slipwave.compare import compare_test
from slipwave.events import detect_events, events_dataset, segment_phases
from slipwave.fit import FitSettings, chosen_law, fit_test, measured_events
from slipwave.fits import fits_table
from slipwave.report import (
    pairing_summary,
    write_test_page,
)
from slipwave.setup import read_test_setup
from slipwave.simulate import replay_test, sequence_scatter

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
POPPLER = shutil.which("pdftoppm")
needs_chromium = pytest.mark.skipif(CHROMIUM is None, reason="Debian's chromium is not "
                                    "installed (.ci/run installs it with apt-get)")
needs_poppler = pytest.mark.skipif(POPPLER is None, reason="poppler-utils (pdftoppm) is not "
                                   "installed (.ci/run installs it with apt-get)")

CHECK = """<script>
window.addEventListener("load", () => {
  const images = [...document.images];
  const broken = images.filter(i => !(i.complete && i.naturalWidth > 0)).length;
  const limit = window.innerWidth + 1;
  const outside = [...document.querySelectorAll("body *")]
    .filter(e => e.getBoundingClientRect().right > limit && !e.closest(".wide"))
    .map(e => e.tagName);
  document.body.setAttribute("data-check", JSON.stringify({
    images: images.length, broken: broken, outside: outside,
    page: document.documentElement.scrollWidth, window: window.innerWidth}));
});
</script>"""


def chromium_check(page: Path, width: int) -> dict:
    """Load a page in headless Chromium at ``width`` px; what its check script found."""
    probe = page.with_name(f"probe-{page.name}")
    probe.write_text(page.read_text().replace("</body>", CHECK + "</body>"))
    run = subprocess.run(
        [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
         "--no-first-run", "--disable-background-networking", "--disable-component-update",
         "--disable-sync", f"--user-data-dir={page.parent / 'chromium-profile'}",
         f"--window-size={width},900", "--virtual-time-budget=20000", "--dump-dom",
         probe.as_uri()], capture_output=True, text=True, timeout=180, check=False)
    found = re.search(r'data-check="([^"]*)"', run.stdout)
    assert found, f"no check in the page Chromium rendered: {run.stderr[-2000:]}"
    return json.loads(found.group(1).replace("&quot;", '"'))


def pdf_facts(pdf: Path) -> tuple[int, str, int]:
    """Pages (rasterised by pdftoppm), text, and images of a PDF."""
    out = pdf.parent / f"{pdf.stem}-page"
    subprocess.run(["pdftoppm", "-r", "30", "-png", str(pdf), str(out)], check=True,
                   timeout=120)
    pages = len(list(pdf.parent.glob(f"{pdf.stem}-page-*.png")))
    text = subprocess.run(["pdftotext", "-layout", str(pdf), "-"], capture_output=True,
                          text=True, check=True).stdout
    listing = subprocess.run(["pdfimages", "-list", str(pdf)], capture_output=True, text=True,
                             check=True).stdout.splitlines()[2:]
    return pages, text, len(listing)


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """A short virtual test's report in full, partial reports, and the campaign report."""
    folder = tmp_path_factory.mktemp("reports")
    spec = BenchTest("v", elements=24, duration=90.0, video="none", fs=0.9, fd=0.6,
                     fs_final=None)
    result = simulate_test(spec, seed=4)
    recording = result.recording
    setup = read_test_setup(recording, {"test_id": "v", "youngs_modulus_mpa": "7",
                                        "poisson_ratio": "0.48", "edge_reference": "frame"})
    fit = fit_test(setup, measured_events(recording), FitSettings.from_values(
        {"elements": 24, "members": 2, "design": 3, "refinements": 0, "samples": 300,
         "predictive_members": 3, "mesh_check": True}),
        laws=["coulomb"])
    replay = replay_test(setup, chosen_law(fit), min_drop=0.3, elements=24)
    table = detect_events(recording, gross_edge_ratio=replay.recording.attrs["gross_edge_ratio"])
    events = events_dataset(table, segment_phases(recording, table))
    scatter = sequence_scatter(setup, chosen_law(fit), min_drop=0.3, elements=24,
                               gross_edge_ratio=replay.recording.attrs["gross_edge_ratio"])
    comparison = compare_test(table, replay.recording, replay.simulation, min_drop=0.3,
                              scatter=scatter)
    simulated_events = comparison.attrs["simulated_events"]
    pairing = pairing_summary(recording, events, fit, comparison, replay.recording,
                              simulated_events, replay.contact)
    pages = {"full": folder / "v.html"}
    write_test_page(recording, pages["full"], events, None, pairing, pdf=folder / "v.pdf",
                    workers=2)
    pages["serial"] = write_test_page(recording, folder / "serial.html", events, None, pairing)
    # a law simulated at other parameters than the medians (no figures: the words only)
    noted = {**pairing, "figures": dict.fromkeys(pairing["figures"]),
             "simulated": {"fs": 0.8123, "fd": 0.6012},
             "simulated_note": "The solver does not follow the posterior medians here.",
             "scatter_left_out": [{"fs": 0.9, "fd": 0.606}]}
    pages["noted"] = write_test_page(recording, folder / "noted.html", events, None, noted)
    # partly missing: no simulation at all; a T-only recording
    pages["measured"] = write_test_page(recording, folder / "measured.html", events,
                                        pdf=folder / "measured.pdf")
    force = recording[["T"]].assign_attrs(recording.attrs)
    pages["force"] = write_test_page(force, folder / "force.html", pdf=folder / "force.pdf")
    summary = pd.DataFrame([{"test_id": "v", "gross_slip_waves": 2, "partial_slip_waves": 3,
                             "static_ratio_mean": 0.7, "static_ratio_ci_low": 0.69,
                             "static_ratio_ci_high": 0.71, "dynamic_ratio_mean": 0.6}])
    content = campaign_summary(summary, fits_table([fit]), {"v": {
        "test_id": "v", "verdicts": comparison["verdict"].value_counts().to_dict()}})
    pages["campaign"] = write_campaign_report(content, folder / "campaign.html",
                                              pdf=folder / "campaign.pdf")
    return pages, comparison, replay.recording.attrs["gross_edge_ratio"], fit["edge_threshold"]


def test_full_report_says_what_it_compares(built):
    pages, comparison, *_ = built
    html = pages["full"].read_text()
    for heading in ("Configuration", "Comparison", "Signals", "First gross slips",
                    "Space and time", "Friction laws", "Events", "Channels"):
        assert f"<h2>{heading}</h2>" in html
    for feature in comparison["feature"]:
        assert feature.replace("|", "|") in html
    # the simulated values with the law's own scatter, where it has one (a feature the
    # simulation lacks, shown "–", has no value to put it beside)
    simulated = pd.to_numeric(comparison["simulated"], errors="coerce")
    scattered = comparison[(comparison["scatter"] > 0) & np.isfinite(simulated)]
    assert len(scattered) and all(f"± {value:.2g}</span>" in html
                                  for value in scattered["scatter"])
    assert "no video: the simulated zones and kymograph are shown alone" in html
    assert "measured: least squares of DT on t and T" in html  # sources of the setup
    # the threshold the events were told by (the simulation's), and the fit's own
    _, _, detection, fitted = built
    assert f"DG/DD jump ratio of {detection:.3g} or more, read off the simulated slips" in html
    assert f"the fit judged its laws' features by {fitted:.3g}" in html
    # the chosen law at twice the mesh, each parameter's change, and what Coulomb's is
    assert "The chosen law searched again at 48 elements, twice the fit's 24" in html
    # the chosen law's posterior predictive, feature by feature, and what it says
    assert "The chosen law against the measurement." in html
    assert html.count('<span class="agrees">agrees</span>') + html.count(
        '<span class="differs">differs</span>') >= 13
    assert ("reproduces every feature" in html) != ("does not reproduce this recording" in html)
    assert "has no length scale: its coefficients are the mesh-dependent limit" in html
    campaign = pages["campaign"].read_text()
    assert "fs, fd at twice the mesh" in campaign and campaign.count(" %, ") >= 1


def test_figures_drawn_on_two_processes_are_those_drawn_on_one(built):
    pages, *_ = built
    full = pages["full"].read_text()
    assert full == pages["serial"].read_text()
    assert full.count("data:image/png;base64,") >= 5


def test_page_says_which_law_is_simulated_when_not_the_medians(built):
    pages, *_ = built
    assert "The law simulated." not in pages["full"].read_text()  # the medians
    noted = pages["noted"].read_text()
    assert ("<strong>The law simulated.</strong> The solver does not follow the posterior "
            "medians here. Its parameters: fs 0.8123, fd 0.6012.") in noted


def test_page_says_which_neighbours_the_scatter_leaves_out(built):
    pages, *_ = built
    assert "The scatter leaves out" not in pages["full"].read_text()  # every one followed
    assert ("The scatter leaves out 1 of the neighbours, which the solver does not follow: "
            "fs 0.9, fd 0.606; it is taken over the law and the others.") in (
        pages["noted"].read_text())


def test_partial_reports_say_what_is_missing(built):
    pages, *_ = built
    measured = pages["measured"].read_text()
    assert "no simulation: the measurement alone" in measured
    assert "<h2>Events</h2>" in measured and "<h2>Comparison</h2>" not in measured
    force = pages["force"].read_text()
    assert "no simulation" in force and "<h2>Signals</h2>" in force


@needs_chromium
@pytest.mark.parametrize("name", ["full", "measured", "force", "campaign"])
@pytest.mark.parametrize("width", [1280, 800])
def test_pages_render_in_chromium_without_broken_images_or_overflow(built, name, width):
    pages, *_ = built
    found = chromium_check(pages[name], width)
    assert found["images"] >= 1 and found["broken"] == 0
    assert found["page"] <= found["window"] and not found["outside"], found


@needs_poppler
@pytest.mark.parametrize(("name", "sections", "least_images"), [
    ("full", ("Configuration", "Comparison", "Signals", "First gross slips", "Space and time",
              "Friction laws", "Events", "Channels", "Metadata"), 7),
    ("measured", ("Signals", "Events", "Channels"), 1),
    ("force", ("Signals", "Channels"), 1),
    ("campaign", ("Tests", "T/|N| and fitted friction against H/L"), 1),
])
def test_pdfs_have_their_pages_sections_and_figures(built, name, sections, least_images):
    pages, comparison, *_ = built
    pdf = pages[name].with_suffix(".pdf")
    count, text, images = pdf_facts(pdf)
    assert count >= 1 and f"page 1 of {count}" in text
    for section in sections:
        assert section in text, section
    assert images >= least_images
    if name == "full":
        assert count >= 4
        # the comparison table whole: every feature, every verdict
        flat = " ".join(text.split())
        for feature in comparison["feature"]:
            assert " ".join(feature.split()[:3]) in flat, feature


def test_figure_workers_die_quietly_when_the_pool_stops_them(capfd):
    # The command line turns SIGTERM into KeyboardInterrupt (outputs unwind whole); the
    # forked figure workers inherited it, so the pool's own SIGTERM at its end made them
    # unwind inside the task queue's lock, which once left a report waiting for ever.
    import signal

    from matplotlib.figure import Figure

    from slipwave.plot import figures_png

    def terminate(signum, frame):  # as the command line does: outputs unwind whole
        raise KeyboardInterrupt

    figures = []
    for _ in range(3):
        figure = Figure(figsize=(1, 1))
        figure.add_subplot().plot([0, 1])
        figures.append(figure)
    previous = signal.signal(signal.SIGTERM, terminate)
    try:
        for _ in range(40):  # about one pool in five printed a worker's traceback
            assert len(figures_png(figures, workers=2, dpi=20)) == 3
    finally:
        signal.signal(signal.SIGTERM, previous)
    assert "KeyboardInterrupt" not in capfd.readouterr().err
