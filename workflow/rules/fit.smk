rule fit:
    """Friction laws fitted to one test through the solver, on its own configuration."""
    input:
        recording="results/{test_id}/recording.nc",
        solver=ancient("results/solver.json"),
    output:
        report(
            "results/{test_id}/fit.json",
            caption="../report/fit.rst",
            category="Fits",
            labels={"test": "{test_id}"},
        ),
    log:
        "results/logs/fit/{test_id}.log",
    params:
        settings=setup_settings,
        laws=" ".join(config["fit"]["laws"]),
        elements=config["fit"]["elements"],
        tunables=fit_options,
        load_calibration=config["fit"]["load_calibration"],
        mesh_check="on" if config["fit"]["mesh_check"] else "off",
        detection=detection_options,
        cache=cache_option(config),
    # the longest jobs first (a minute or more each): the map's rows and the short stages
    # fill the cores around them, instead of a last fit running alone
    priority: 50
    threads: 1
    resources:
        mem_mb=scaled_memory(1500),
        runtime=60,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave fit {input.recording:q} -o {output:q} "
        "--setting {params.settings} --laws {params.laws} --elements {params.elements} "
        "{params.tunables} "
        "--load-calibration {params.load_calibration} --mesh-check {params.mesh_check} "
        "{params.detection} {params.cache} "
        "> {log:q} 2>&1"

