rule report:
    """The report of one test, HTML and PDF: configuration, verdicts, measured against
    simulated, space-time, frames, friction laws, the map; what is missing, said."""
    input:
        unpack(report_inputs),
    output:
        html=report(
            "reports/{test_id}.html",
            caption="../report/report.rst",
            category="Tests",
            labels={"test": "{test_id}", "format": "HTML"},
        ),
        pdf=report(
            "reports/{test_id}.pdf",
            caption="../report/report.rst",
            category="Tests",
            labels={"test": "{test_id}", "format": "PDF"},
        ),
    log:
        "results/logs/report/{test_id}.log",
    params:
        video=video_options,
        pairing=pairing_options,
    # one core: a second draws the figures no faster (7.4 s against 7.6 s for a bench
    # test), and a report asking for two waits for a fit to end instead of running beside it
    threads: 1
    resources:
        mem_mb=scaled_memory(3000),
        runtime=15,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave report {input.recording:q} --events {input.events:q} {params.video} "
        "{params.pairing} -o {output.html:q} --pdf {output.pdf:q} --threads {threads} "
        "> {log:q} 2>&1"

