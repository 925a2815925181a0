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
    # the figures are drawn on the job's cores (most of a report's time)
    threads: 2
    resources:
        mem_mb=scaled_memory(3000),
        runtime=15,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave report {input.recording:q} --events {input.events:q} {params.video} "
        "{params.pairing} -o {output.html:q} --pdf {output.pdf:q} --threads {threads} "
        "> {log:q} 2>&1"

