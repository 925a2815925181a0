rule fit_waves:
    """A filmed test's rate-and-state law (a, b - a, Dc, mu0) fitted on its card's cycle and
    its video's waves through quasi-dynamic runs of its slab; the simulate_waves stage then
    runs the test under it."""
    input:
        fit="results/{test_id}/fit.json",
        recording="results/{test_id}/recording.nc",
        waves="results/{test_id}/waves.csv",
        kymograph="results/{test_id}/kymograph.nc",
    output:
        report(
            "results/{test_id}/fit_waves.json",
            caption="../report/fit_waves.rst",
            category="Fits",
            labels={"test": "{test_id}", "law": "rate-and-state"},
        ),
    log:
        "results/logs/fit_waves/{test_id}.log",
    params:
        tunables=fit_waves_options,
        detection=detection_options,
    # the longest jobs (two to six minutes on two cores): first, the rest around them
    priority: 60
    threads: 2
    resources:
        mem_mb=scaled_memory(3000),
        runtime=60,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave fit-waves --fit {input.fit:q} --recording {input.recording:q} "
        "--waves {input.waves:q} --kymograph {input.kymograph:q} {params.tunables} "
        "{params.detection} --processes {threads} -o {output:q} > {log:q} 2>&1"
