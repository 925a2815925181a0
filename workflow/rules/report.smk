rule test_page:
    """The HTML page of one test: channels and T/|N| against time, phases and slips."""
    input:
        recording="results/{test_id}/recording.nc",
        events="results/{test_id}/events.nc",
    output:
        report(
            "reports/{test_id}.html",
            caption="../report/test_page.rst",
            category="Tests",
            labels={"test": "{test_id}"},
        ),
    log:
        "results/logs/test_page/{test_id}.log",
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave report {input.recording:q} --events {input.events:q} -o {output:q} "
        "> {log:q} 2>&1"
