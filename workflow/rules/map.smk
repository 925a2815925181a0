# The behaviour map (the paper's figure 2): the H/L rows dealt to map.row_jobs jobs of
# about equal cost (each runs its rows in one process, paying its start-up once), each
# job's f range in shards when map.shard_size is set, at the map's mesh and at the
# coarser mesh of its band (map.band_elements); then the pieces joined, the behaviours
# named, the band where the map still moves with the mesh marked, and the map drawn. On a cluster, the jobs are batched by their group
# (profiles/slurm: group-components).


rule map_row:
    """A job's H/L rows (or a shard of their friction coefficients) at one mesh."""
    input:
        ancient("results/solver.json"),
    output:
        "results/map/rows/{elements}/job{job}-{shard}.nc",
    log:
        "results/logs/map/{elements}/job{job}-{shard}.log",
    params:
        height_ratios=lambda wildcards: " ".join(f"{r:g}" for r in MAP_JOBS[int(wildcards.job)]),
        frictions=" ".join(str(v) for v in config["map"]["frictions"]),
        settings=map_row_options,
        shard_size=config["map"]["shard_size"],
        memory_gb=lambda wildcards, resources: resources.mem_mb / 1000,
        cache=cache_option(config),
    group:
        "map_rows"
    threads: 1
    resources:
        mem_mb=scaled_memory(config["map"]["mem_mb"]),
        runtime=20,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave map row --height-ratio {params.height_ratios} "
        "--frictions {params.frictions} {params.settings} --shard {wildcards.shard} "
        "--shard-size {params.shard_size} --memory-limit {params.memory_gb} "
        "{params.cache} -o {output:q} > {log:q} 2>&1"


rule map_assemble:
    """The map: map.nc (H/L x f: behaviour, succession, L, first events, T/N, the mesh's
    band), map.csv, legend."""
    input:
        rows=map_shard_files(MAP_ELEMENTS),
        band_rows=[path for mesh in MAP_BAND_ELEMENTS for path in map_shard_files(mesh)],
    output:
        netcdf="results/map/map.nc",
        csv="results/map/map.csv",
        legend=report(
            "results/map/legend.md", caption="../report/legend.rst", category="Behaviour map"
        ),
    log:
        "results/logs/map/map.log",
    params:
        band=map_band_options,
    threads: 1
    resources:
        mem_mb=scaled_memory(2000),
        runtime=10,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave map assemble {input.rows:q} {params.band} -o {output.netcdf:q} "
        "--csv {output.csv:q} --legend {output.legend:q} > {log:q} 2>&1"


rule map_figures:
    """The map figure with the campaign's tests, and one zone history per behaviour."""
    input:
        map="results/map/map.nc",
        summary="results/summary.csv",
        solver=ancient("results/solver.json"),
    output:
        figure=report(
            "results/map/map.png", caption="../report/map.rst", category="Behaviour map"
        ),
        zones=report(
            "results/map/zones.png",
            caption="../report/zones.rst",
            category="Behaviour map",
        ),
    log:
        "results/logs/map/map_figures.log",
    params:
        tests=" ".join(height_ratio_pairs(campaign)),
        cache=cache_option(config),
    threads: 1
    resources:
        mem_mb=scaled_memory(3000),
        runtime=15,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave map figures {input.map:q} --figure {output.figure:q} "
        "--zones {output.zones:q} --summary {input.summary:q} --test-ratio {params.tests} "
        "{params.cache} > {log:q} 2>&1"
