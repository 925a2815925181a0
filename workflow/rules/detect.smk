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
        detection=detection_options,
        simulated=threshold_option,
    threads: 1
    resources:
        mem_mb=scaled_memory(1000),
        runtime=10,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave detect {input.recording:q} -o {output.csv:q} --netcdf {output.netcdf:q} "
        "{params.detection} {params.simulated} "
        "> {log:q} 2>&1"
