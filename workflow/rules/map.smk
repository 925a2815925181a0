# The behaviour map (the paper's figure 2): one job per H/L (the slab condensed once),
# then the rows joined, the behaviours named and the map drawn.


rule map_row:
    """Every friction coefficient of the map at one H/L."""
    output:
        "results/map/rows/hl{height_ratio}.nc",
    log:
        "results/logs/map/hl{height_ratio}.log",
    params:
        frictions=" ".join(str(v) for v in config["map"]["frictions"]),
        settings=map_row_options,
    threads: 1
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave map row --height-ratio {wildcards.height_ratio} "
        "--frictions {params.frictions} {params.settings} -o {output:q} > {log:q} 2>&1"


rule map:
    """The map: map.nc (H/L x f: behaviour, succession, L, first events, T/N), map.csv, legend."""
    input:
        expand("results/map/rows/hl{height_ratio}.nc", height_ratio=MAP_HEIGHT_RATIOS),
    output:
        netcdf="results/map/map.nc",
        csv="results/map/map.csv",
        legend=report(
            "results/map/legend.md", caption="../report/legend.rst", category="Behaviour map"
        ),
    log:
        "results/logs/map/map.log",
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave map assemble {input:q} -o {output.netcdf:q} --csv {output.csv:q} "
        "--legend {output.legend:q} > {log:q} 2>&1"


rule map_figures:
    """The map figure with the campaign's tests, and one zone history per behaviour."""
    input:
        map="results/map/map.nc",
        summary="results/summary.csv",
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
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave map figures {input.map:q} --figure {output.figure:q} "
        "--zones {output.zones:q} --summary {input.summary:q} --test-ratio {params.tests} "
        "> {log:q} 2>&1"
