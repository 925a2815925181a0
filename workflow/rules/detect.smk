rule detect:
    """Slip events of one test: T drops classified by the DG/DD jumps (the threshold read
    off the test's simulated slips), phases, T/|N|."""
    input:
        unpack(detect_inputs),
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
        threshold=config["detection"]["threshold"],
        max_spike=config["detection"]["max_spike"],
        max_duration=config["detection"]["max_duration"],
        min_fall_rate=config["detection"]["min_fall_rate"],
        gross_edge_ratio=threshold_option,
        edge_convention=lambda wildcards: edge_convention(config, test_row(wildcards)),
    threads: 1
    resources:
        mem_mb=scaled_memory(1000),
        runtime=10,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave detect {input.recording:q} -o {output.csv:q} --netcdf {output.netcdf:q} "
        "--test-id {wildcards.test_id:q} --threshold {params.threshold} "
        "--max-spike {params.max_spike} --max-duration {params.max_duration} "
        "--min-fall-rate {params.min_fall_rate} {params.gross_edge_ratio} "
        "--edge-convention {params.edge_convention} "
        "> {log:q} 2>&1"
