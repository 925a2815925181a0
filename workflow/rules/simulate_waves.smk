rule simulate_waves:
    """A filmed test simulated quasi-dynamically under rate-and-state friction: its waves
    with a speed, in the video's columns, for the compare stage."""
    input:
        fit="results/{test_id}/fit.json",
    output:
        run="results/{test_id}/simulated/quasi_dynamic.nc",
        waves="results/{test_id}/simulated/waves.csv",
    log:
        "results/logs/simulate_waves/{test_id}.log",
    params:
        law=" ".join(
            f"--{key.replace('_', '-')} {config['simulate_waves'][key]}"
            for key in ("a", "b", "dc_um", "mu0", "v0_um_s")
        ),
        elements=config["simulate_waves"]["elements"],
        field_rate=config["simulate_waves"]["field_rate_hz"],
    threads: 1
    resources:
        mem_mb=scaled_memory(1500),
        runtime=15,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave simulate-waves --fit {input.fit:q} {params.law} "
        "--elements {params.elements} --field-rate {params.field_rate} "
        "-o {output.run:q} --waves {output.waves:q} > {log:q} 2>&1"
