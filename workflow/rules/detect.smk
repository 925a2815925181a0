rule detect:
    """Slip events of one test: T drops classified by the DG/DD jumps, phases, T/|N|."""
    input:
        "results/{test_id}/recording.nc",
    output:
        csv=report(
            "results/{test_id}/events.csv",
            caption="../report/events.rst",
            category="Events",
            labels={"test": "{test_id}"},
        ),
        netcdf="results/{test_id}/events.nc",
    log:
        "results/logs/detect/{test_id}.log",
    params:
        options=lambda wildcards: detection_arguments(
            config, tests.loc[wildcards.test_id, "gross_edge_ratio"]
        ),
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave detect {input:q} -o {output.csv:q} --netcdf {output.netcdf:q} "
        "--test-id {wildcards.test_id:q} {params.options} > {log:q} 2>&1"


rule summary:
    """The campaign summary: one row per test (T/|N| at gross slips, waves, phases)."""
    input:
        expand("results/{test_id}/events.nc", test_id=TEST_IDS),
    output:
        report("results/summary.csv", caption="../report/summary.rst", category="Campaign"),
    log:
        "results/logs/summary.log",
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave summarize {input:q} -o {output:q} > {log:q} 2>&1"
