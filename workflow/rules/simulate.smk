rule simulate:
    """One test simulated with its fitted law: a recording in the measurement's shape,
    the zone history and the simulated kymograph; and the law's neighbours, a load
    cell's calibration apart, for the simulation's own scatter."""
    input:
        fit="results/{test_id}/fit.json",
        solver=ancient("results/solver.json"),
    output:
        recording="results/{test_id}/simulated/recording.nc",
        contact="results/{test_id}/simulated/contact.nc",
        steps="results/{test_id}/simulated/steps.nc",
        scatter="results/{test_id}/simulated/scatter.csv",
    log:
        "results/logs/simulate/{test_id}.log",
    params:
        band=config["video"]["band_mm"],
        detection=detection_options,
        cache=cache_option(config),
    threads: 1
    resources:
        mem_mb=scaled_memory(1500),
        runtime=15,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave simulate --fit {input.fit:q} -o {output.recording:q} "
        "--contact {output.contact:q} --steps {output.steps:q} --scatter {output.scatter:q} "
        "--band {params.band[0]} {params.band[1]} {params.detection} {params.cache} "
        "> {log:q} 2>&1"
