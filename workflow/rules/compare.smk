rule compare:
    """Measured against simulated, feature by feature, and the test on the map."""
    input:
        unpack(compare_inputs),
    output:
        table=report(
            "results/{test_id}/comparison.csv",
            caption="../report/comparison.rst",
            category="Comparisons",
            labels={"test": "{test_id}"},
        ),
        summary="results/{test_id}/comparison.json",
        simulated_events="results/{test_id}/simulated/events.csv",
    log:
        "results/logs/compare/{test_id}.log",
    params:
        waves=lambda wildcards, input: (
            f"--waves {shlex.quote(str(input.waves))}" if "waves" in input.keys() else ""
        ),
        simulated_waves=lambda wildcards, input: (
            f"--simulated-waves {shlex.quote(str(input.simulated_waves))}"
            if "simulated_waves" in input.keys()
            else ""
        ),
        detection=detection_options,
    threads: 1
    resources:
        mem_mb=scaled_memory(1500),
        runtime=10,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave compare {input.events:q} --simulated {input.simulated:q} "
        "--steps {input.steps:q} --scatter {input.scatter:q} --fit {input.fit:q} {params.waves} {params.simulated_waves} --map {input.map:q} "
        "-o {output.table:q} --json {output.summary:q} "
        "--simulated-events {output.simulated_events:q} {params.detection} > {log:q} 2>&1"
