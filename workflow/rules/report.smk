rule report:
    """The HTML page of one test: channels, phases and slips; kymograph and frames if filmed."""
    input:
        unpack(report_inputs),
    output:
        report(
            "reports/{test_id}.html",
            caption="../report/report.rst",
            category="Tests",
            labels={"test": "{test_id}"},
        ),
    log:
        "results/logs/report/{test_id}.log",
    params:
        video=video_options,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave report {input.recording:q} --events {input.events:q} {params.video} "
        "-o {output:q} > {log:q} 2>&1"
