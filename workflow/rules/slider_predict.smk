rule slider_predict:
    """A record's posterior predictive (a check on the fitted records, a prediction on the rest)."""
    input:
        record="results/sliders/{record_id}/record.nc",
        posterior="results/sliders/posterior.nc",
    output:
        "results/sliders/{record_id}/prediction.json",
    log:
        "results/logs/slider_predict/{record_id}.log",
    params:
        draws=config["sliders"]["draws"],
        members=config["sliders"]["members"],
        seed=config["sliders"]["seed"],
    threads: 1
    resources:
        mem_mb=1000,
        runtime=30,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave slider-predict {input.record:q} --posterior {input.posterior:q} "
        "-o {output:q} --draws {params.draws} --members {params.members} "
        "--seed {params.seed} > {log:q} 2>&1"
