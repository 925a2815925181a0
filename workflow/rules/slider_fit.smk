rule slider_fit:
    """Rate-and-state friction fitted jointly on the records whose role is fit (only those)."""
    input:
        expand("results/sliders/{record_id}/record.nc", record_id=SLIDER_FIT_IDS),
    output:
        fit="results/sliders/fit.json",
        posterior="results/sliders/posterior.nc",
    log:
        "results/logs/slider_fit.log",
    params:
        settings=slider_fit_options(config["sliders"]),
    threads: 2
    resources:
        mem_mb=1500,
        runtime=60,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave slider-fit {input:q} -o {output.fit:q} --posterior {output.posterior:q} "
        "{params.settings} --processes {threads} > {log:q} 2>&1"
