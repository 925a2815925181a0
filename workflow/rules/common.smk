# Input and parameter functions shared by the rules: lookups in the campaign
# table, no logic (that lives in slipwave.campaign).


def test_row(wildcards):
    return campaign.loc[wildcards.test_id]


def report_inputs(wildcards):
    inputs = {
        "recording": f"results/{wildcards.test_id}/recording.nc",
        "events": f"results/{wildcards.test_id}/events.nc",
    }
    frames = test_row(wildcards)["frames"]
    if frames:
        inputs.update(
            kymograph=f"results/{wildcards.test_id}/kymograph.nc",
            waves=f"results/{wildcards.test_id}/waves.csv",
            fused=f"results/{wildcards.test_id}/events_video.csv",
            clock=f"results/{wildcards.test_id}/clock.json",
            frames=frames,
        )
    return inputs


def frame_rate_option(wildcards):
    fps = test_row(wildcards)["fps"]
    return f"--fps {fps}" if fps else ""


def video_options(wildcards, input):
    if "kymograph" not in input.keys():
        return ""
    return (
        f"--kymograph {input.kymograph} --waves {input.waves} --fused {input.fused} "
        f"--clock {input.clock} --frames {input.frames}"
    )


def map_row_options(wildcards):
    settings = config["map"]
    friction = "on" if settings["normal_friction"] else "off"
    return (
        f"--elements {settings['elements']} --normal-control {settings['normal_control']} "
        f"--normal-friction {friction} --min-zone {settings['min_zone_mm']}"
    )
