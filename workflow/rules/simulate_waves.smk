rule simulate_waves:
    """A filmed test simulated quasi-dynamically under rate-and-state friction (its fitted
    law with fit_waves enabled, else the config's) and filmed at its video's frame rate: its
    waves with a speed, measured as the video's, for the compare stage; and the run's
    slip-rate fronts."""
    input:
        unpack(simulate_waves_inputs),
    output:
        run="results/{test_id}/simulated/quasi_dynamic.nc",
        film="results/{test_id}/simulated/kymograph.nc",
        waves="results/{test_id}/simulated/waves.csv",
        fronts="results/{test_id}/simulated/fronts.csv",
    log:
        "results/logs/simulate_waves/{test_id}.log",
    params:
        law=law_options,
        elements=config["simulate_waves"]["elements"],
        field_rate=config["simulate_waves"]["field_rate_hz"],
    threads: 1
    resources:
        mem_mb=scaled_memory(1500),
        runtime=20,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave simulate-waves --fit {input.fit:q} --kymograph {input.kymograph:q} "
        "{params.law} --elements {params.elements} --field-rate {params.field_rate} "
        "-o {output.run:q} --film {output.film:q} --waves {output.waves:q} "
        "--fronts {output.fronts:q} > {log:q} 2>&1"
