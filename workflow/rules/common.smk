# Input and parameter functions shared by the rules: lookups in the campaign
# table and the config, no logic (that lives in slipwave.campaign).
import shlex


def scaled_memory(megabytes):
    """A job's memory, MB, growing with each retry (a job killed for memory gets more)."""
    return lambda wildcards, attempt: megabytes * attempt


def slider_bench_options(wildcards):
    return slider_ingest_options(SLIDERS.loc[wildcards.record_id])


def test_row(wildcards):
    return campaign.loc[wildcards.test_id]


def report_inputs(wildcards):
    test = wildcards.test_id
    inputs = {
        "recording": f"results/{test}/recording.nc",
        "events": f"results/{test}/events.nc",
    }
    if config["fit"]["enabled"]:
        inputs.update(
            fit=f"results/{test}/fit.json",
            comparison=f"results/{test}/comparison.csv",
            comparison_json=f"results/{test}/comparison.json",
            simulated=f"results/{test}/simulated/recording.nc",
            simulated_events=f"results/{test}/simulated/events.csv",
            contact=f"results/{test}/simulated/contact.nc",
            map="results/map/map.nc",
        )
    frames = test_row(wildcards)["frames"]
    if frames:
        inputs.update(
            kymograph=f"results/{wildcards.test_id}/kymograph.nc",
            waves=f"results/{wildcards.test_id}/waves.csv",
            fused=f"results/{wildcards.test_id}/events_video.csv",
            clock=f"results/{wildcards.test_id}/clock.json",
            frames=frames,
        )
        if config["fit"]["enabled"] and config["simulate_waves"]["enabled"]:
            # the test run quasi-dynamically needs its fit.json (its setup)
            inputs.update(
                quasi_dynamic=f"results/{test}/simulated/quasi_dynamic.nc",
                simulated_waves=f"results/{test}/simulated/waves.csv",
                simulated_fronts=f"results/{test}/simulated/fronts.csv",
                simulated_film=f"results/{test}/simulated/kymograph.nc",
            )
            if config["fit_waves"]["enabled"]:
                inputs.update(waves_fit=f"results/{test}/fit_waves.json")
    return inputs


def frame_rate_option(wildcards):
    fps = test_row(wildcards)["fps"]
    return f"--fps {fps}" if fps else ""


def video_options(wildcards, input):
    if "kymograph" not in input.keys():
        return ""
    return " ".join(
        f"--{name.replace('_', '-')} {shlex.quote(str(input[name]))}"
        for name in (
            "kymograph", "waves", "fused", "clock", "frames", "quasi_dynamic", "simulated_waves",
            "simulated_fronts", "simulated_film", "waves_fit",
        )
        if name in input.keys()
    )


def map_row_options(wildcards):
    settings = config["map"]
    friction = "on" if settings["normal_friction"] else "off"
    return (
        f"--elements {wildcards.elements} --normal-control {settings['normal_control']} "
        f"--normal-friction {friction} --min-zone {settings['min_zone_mm']}"
    )


def map_shard_files(elements):
    """Every job's and shard's rows of the map at one mesh."""
    return [
        f"results/map/rows/{elements}/job{job}-{shard}.nc"
        for job in range(len(MAP_JOBS))
        for shard in range(MAP_SHARDS)
    ]


def map_band_options(wildcards, input):
    if not input.band_rows:
        return ""
    rows = " ".join(shlex.quote(str(path)) for path in input.band_rows)
    return f"--band-rows {rows} --band-steps {config['map']['band_steps']}"


def setup_settings(wildcards):
    return " ".join(setup_cells(test_row(wildcards)))


def compare_inputs(wildcards):
    inputs = {
        "events": f"results/{wildcards.test_id}/events.nc",
        "simulated": f"results/{wildcards.test_id}/simulated/recording.nc",
        "steps": f"results/{wildcards.test_id}/simulated/steps.nc",
        "scatter": f"results/{wildcards.test_id}/simulated/scatter.csv",
        "fit": f"results/{wildcards.test_id}/fit.json",
        "map": "results/map/map.nc",
    }
    if test_row(wildcards)["frames"]:
        inputs["waves"] = f"results/{wildcards.test_id}/waves.csv"
        if config["simulate_waves"]["enabled"]:
            inputs["simulated_waves"] = f"results/{wildcards.test_id}/simulated/waves.csv"
    return inputs


def detect_inputs(wildcards):
    inputs = {"recording": f"results/{wildcards.test_id}/recording.nc"}
    if config["fit"]["enabled"]:
        inputs["simulated"] = f"results/{wildcards.test_id}/simulated/recording.nc"
    return inputs


def threshold_option(wildcards, input):
    if "simulated" in input.keys():
        return f"--simulated {shlex.quote(str(input.simulated))}"
    return f"--gross-edge-ratio {config['detection']['gross_edge_ratio']}"


def detection_options(wildcards):
    """The campaign's detection settings, the same for every stage that detects slips."""
    settings = config["detection"]
    convention = edge_convention(config, test_row(wildcards))
    return (
        f"--threshold {settings['threshold']} --max-spike {settings['max_spike']} "
        f"--max-duration {settings['max_duration']} "
        f"--min-fall-rate {settings['min_fall_rate']} --edge-convention {convention}"
    )


def fit_options(wildcards):
    """The fit's ensemble, measurement and search settings, as slipwave fit's options."""
    return " ".join(
        f"--{key.replace('_', '-')} {config['fit'][key]}"
        for key in ("members", "stiffness_error", "speed_error", "step_jitter",
                    "ratio_error", "time_error_s", "design", "refinements", "draw_temperature", "samples",
                    "predictive_members", "seed")
    )


def fit_waves_options(wildcards):
    """The rate-and-state fit's settings, as slipwave fit-waves' options."""
    return " ".join(
        f"--{key.replace('_', '-')} {config['fit_waves'][key]}"
        for key in ("elements", "members", "design", "refinements", "samples", "mesh_checks",
                    "seed")
    )


def simulate_waves_inputs(wildcards):
    inputs = {
        "fit": f"results/{wildcards.test_id}/fit.json",
        "kymograph": f"results/{wildcards.test_id}/kymograph.nc",
    }
    if config["fit_waves"]["enabled"]:
        inputs["law_fit"] = f"results/{wildcards.test_id}/fit_waves.json"
    return inputs


def law_options(wildcards, input):
    """The quasi-dynamic run's law: the test's fitted one, else the config's."""
    if "law_fit" in input.keys():
        return f"--law-fit {shlex.quote(str(input.law_fit))}"
    return " ".join(
        f"--{key.replace('_', '-')} {config['simulate_waves'][key]}"
        for key in ("a", "b", "dc_um", "mu0", "v0_um_s")
    )


def pairing_options(wildcards, input):
    names = ("fit", "comparison", "comparison_json", "simulated", "simulated_events",
             "contact", "map")
    return " ".join(
        f"--{name.replace('_', '-')} {shlex.quote(str(input[name]))}"
        for name in names
        if name in input.keys()
    )


def campaign_report_inputs(wildcards):
    inputs = {"summary": "results/summary.csv"}
    if config["fit"]["enabled"]:
        inputs.update(
            fits="results/fits.csv",
            comparisons=expand("results/{test_id}/comparison.json", test_id=TEST_IDS),
            map="results/map/map.nc",
        )
    return inputs


def campaign_options(wildcards, input):
    if "fits" not in input.keys():
        return ""
    comparisons = " ".join(shlex.quote(str(path)) for path in input.comparisons)
    return (
        f"--fits {shlex.quote(str(input.fits))} --comparisons {comparisons} "
        f"--map {shlex.quote(str(input.map))}"
    )
