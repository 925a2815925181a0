rule campaign_report:
    """The campaign report, HTML and PDF: one row per test, T/|N| and fitted friction
    against H/L, the behaviour map with the tests."""
    input:
        unpack(campaign_report_inputs),
    output:
        html=report(
            "reports/campaign.html",
            caption="../report/campaign.rst",
            category="Campaign",
            labels={"format": "HTML"},
        ),
        pdf=report(
            "reports/campaign.pdf",
            caption="../report/campaign.rst",
            category="Campaign",
            labels={"format": "PDF"},
        ),
    log:
        "results/logs/campaign_report.log",
    params:
        pairing=campaign_options,
    threads: 1
    resources:
        mem_mb=scaled_memory(3000),
        runtime=15,
    conda:
        "../envs/slipwave.yaml"
    shell:
        "slipwave campaign-report --summary {input.summary:q} {params.pairing} "
        "-o {output.html:q} --pdf {output.pdf:q} > {log:q} 2>&1"
