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
        "slipwave summary {input:q} -o {output:q} > {log:q} 2>&1"
