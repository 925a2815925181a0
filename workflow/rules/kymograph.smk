rule kymograph:
    """The band above the interface along the contact, frame by frame, from the test's video."""
    input:
        frames=lambda wildcards: test_row(wildcards)["frames"],
    output:
        "results/{test_id}/kymograph.nc",
    log:
        "results/logs/kymograph/{test_id}.log",
    params:
        length=config["video"]["length_mm"],
        band=config["video"]["band_mm"],
        fps=frame_rate_option,
    threads: 1
    resources:
        mem_mb=scaled_memory(1500),
        runtime=20,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave kymograph {input.frames:q} -o {output:q} --test-id {wildcards.test_id:q} "
        "--length {params.length} --band {params.band[0]} {params.band[1]} {params.fps} "
        "> {log:q} 2>&1"
