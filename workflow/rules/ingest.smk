rule ingest:
    """Read a test's acquisition CSV into CF netCDF (N, mm, s)."""
    input:
        csv=lambda wildcards: tests.loc[wildcards.test_id, "csv"],
    output:
        "results/{test_id}/recording.nc",
    log:
        "results/logs/ingest/{test_id}.log",
    params:
        columns=lambda wildcards: column_arguments(config, tests.loc[wildcards.test_id, "columns"]),
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave ingest {input.csv:q} -o {output:q} {params.columns} > {log:q} 2>&1"
