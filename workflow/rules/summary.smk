rule summary:
    """The campaign summary: one row per test (T/|N| at gross slips, waves, phases)."""
    input:
        expand("results/{test_id}/events.nc", test_id=TEST_IDS),
    output:
        report("results/summary.csv", caption="../report/summary.rst", category="Campaign"),
    log:
        "results/logs/summary.log",
    threads: 1
    resources:
        mem_mb=scaled_memory(500),
        runtime=5,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave summary {input:q} -o {output:q} > {log:q} 2>&1"
