rule ingest:
    """Read a test's acquisition CSV into CF netCDF (N, mm, s)."""
    input:
        csv=lambda wildcards: test_row(wildcards)["csv"],
    output:
        "results/{test_id}/recording.nc",
    log:
        "results/logs/ingest/{test_id}.log",
    params:
        columns=lambda wildcards: column_pairs(config, test_row(wildcards)["columns"]),
    # above the fits' (50): the fits need it, and it would otherwise wait behind the
    # map's rows that become ready with it when the compile rule ends
    priority: 60
    threads: 1
    resources:
        mem_mb=scaled_memory(500),
        runtime=10,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave ingest {input.csv:q} -o {output:q} --test-id {wildcards.test_id:q} "
        "--columns {params.columns:q} > {log:q} 2>&1"
