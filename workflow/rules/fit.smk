rule fit:
    """Friction laws fitted to one test through the solver, on its own configuration."""
    input:
        "results/{test_id}/recording.nc",
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
        max_evaluations=config["fit"]["max_evaluations"],
        load_calibration=config["fit"]["load_calibration"],
        edge_convention=lambda wildcards: edge_convention(config, test_row(wildcards)),
    threads: 1
    resources:
        mem_mb=scaled_memory(1500),
        runtime=60,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave fit {input:q} -o {output:q} --test-id {wildcards.test_id:q} "
        "--setting {params.settings} --laws {params.laws} --elements {params.elements} "
        "--max-evaluations {params.max_evaluations} "
        "--load-calibration {params.load_calibration} "
        "--edge-convention {params.edge_convention} > {log:q} 2>&1"


rule fits:
    """The campaign's fits in one table, and the fitted coefficients against H/L."""
    input:
        expand("results/{test_id}/fit.json", test_id=TEST_IDS),
    output:
        table=report("results/fits.csv", caption="../report/fits.rst", category="Fits"),
        plot=report("results/fits.png", caption="../report/fits.rst", category="Fits"),
    log:
        "results/logs/fits.log",
    threads: 1
    resources:
        mem_mb=scaled_memory(500),
        runtime=5,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave fits {input:q} -o {output.table:q} --plot {output.plot:q} > {log:q} 2>&1"
