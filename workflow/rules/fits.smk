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
