# The solver and the detection compiled once, first: jobs that start together on an
# empty numba cache would each compile them (the first two fits both compiled the
# detection's kernels, 3 s each). The rules that simulate take its report as an
# ancient() input: a new report does not make them run again. Two threads: the solver's
# callees compile side by side, then the increment beside the detection.


rule compile:
    """The solver's and the detection's kernels compiled (or loaded from numba's disk
    cache)."""
    output:
        "results/solver.json",
    log:
        "results/logs/compile.log",
    # above two ingests' (60 each): Snakemake's scheduler maximises the sum of the
    # priorities of the jobs it starts together, and this one takes both cores
    priority: 200
    threads: 2
    resources:
        mem_mb=scaled_memory(1000),
        runtime=10,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave compile -o {output:q} --processes {threads} > {log:q} 2>&1"
