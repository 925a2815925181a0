rule test_page:
    """The HTML page of one test: channels, phases and slips; kymograph and frames if filmed."""
    input:
        unpack(page_inputs),
    output:
        report(
            "reports/{test_id}.html",
            caption="../report/test_page.rst",
            category="Tests",
            labels={"test": "{test_id}"},
        ),
    log:
        "results/logs/test_page/{test_id}.log",
    params:
        video=video_options,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave report {input.recording:q} --events {input.events:q} {params.video} "
        "-o {output:q} > {log:q} 2>&1"
