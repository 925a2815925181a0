rule slider_ingest:
    """Read a spring-slider record's MAT file into CF netCDF with its bench and role."""
    input:
        mat=lambda wildcards: SLIDERS.loc[wildcards.record_id, "mat"],
    output:
        "results/sliders/{record_id}/record.nc",
    log:
        "results/logs/slider_ingest/{record_id}.log",
    params:
        bench=slider_bench_options,
    threads: 1
    resources:
        mem_mb=500,
        runtime=10,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave slider-ingest {input.mat:q} -o {output:q} "
        "--record-id {wildcards.record_id:q} {params.bench} > {log:q} 2>&1"
