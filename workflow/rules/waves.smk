rule waves:
    """Sliding waves of the kymograph, the camera clock, and the events with their waves."""
    input:
        kymograph="results/{test_id}/kymograph.nc",
        recording="results/{test_id}/recording.nc",
        events="results/{test_id}/events.nc",
    output:
        waves=report(
            "results/{test_id}/waves.csv",
            caption="../report/waves.rst",
            category="Video",
            labels={"test": "{test_id}"},
        ),
        fused="results/{test_id}/events_video.csv",
        clock="results/{test_id}/clock.json",
    log:
        "results/logs/waves/{test_id}.log",
    threads: 1
    resources:
        mem_mb=scaled_memory(1500),
        runtime=10,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave waves {input.kymograph:q} --recording {input.recording:q} "
        "--events {input.events:q} -o {output.waves:q} --fused {output.fused:q} "
        "--clock {output.clock:q} > {log:q} 2>&1"
