rule slider_report:
    """The spring-slider campaign's page: the law, and record by record its predictions."""
    input:
        fit="results/sliders/fit.json",
        predictions=expand(
            "results/sliders/{record_id}/prediction.json", record_id=SLIDER_IDS
        ),
    output:
        "reports/sliders.html",
    log:
        "results/logs/slider_report.log",
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave slider-report --fit {input.fit:q} {input.predictions:q} "
        "-o {output:q} > {log:q} 2>&1"
