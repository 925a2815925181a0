# Input and parameter functions shared by the rules.


def page_inputs(wildcards):
    inputs = {
        "recording": f"results/{wildcards.test_id}/recording.nc",
        "events": f"results/{wildcards.test_id}/events.nc",
    }
    frames = tests.loc[wildcards.test_id, "frames"]
    if frames:
        inputs.update(
            kymograph=f"results/{wildcards.test_id}/kymograph.nc",
            waves=f"results/{wildcards.test_id}/waves.csv",
            clock=f"results/{wildcards.test_id}/clock.json",
            frames=frames,
        )
    return inputs


def video_options(wildcards, input):
    if "kymograph" not in input.keys():
        return ""
    return (
        f"--kymograph {input.kymograph} --waves {input.waves} --clock {input.clock} "
        f"--frames {input.frames}"
    )
