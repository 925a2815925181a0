# slipwave workflow: friction-bench recordings to answers.
# Run: snakemake --cores 2            (the default campaign of config/config.yaml)
#      snakemake --cores 2 --configfile my_campaign.yaml
#
# One stage, one name: rule <stage> lives in workflow/rules/<stage>.smk, runs
# `slipwave <stage>` and its code is the module the README's stage table names.
import re

from snakemake.utils import min_version, validate

from slipwave.io.atomic import remove_stale_parts
from slipwave.map import deal_rows, friction_grid, map_meshes, shard_count
from slipwave.validation import load_schema, schema_path
from slipwave.slider_campaign import read_slider_campaign, slider_fit_options, slider_ingest_options
from slipwave.campaign import (
    cache_option,
    check_campaign,
    check_stages,
    check_config_files,
    column_pairs,
    edge_convention,
    height_ratio_pairs,
    read_campaign,
    setup_cells,
)

min_version("8.10")


configfile: "config/config.yaml"


# Each config file against the schema first (errors name its line), then the merged
# config: the schema, shipped with the package, carries every default (the library
# reads its defaults from it too), and validate() fills them in.
check_config_files(
    [*workflow.configfiles, *workflow.overwrite_configfiles],
    load_schema("config"),
    command_line=workflow.overwrite_configfiles,
)
validate(config, str(schema_path("config")))


# A job killed outright (out of memory, SIGKILL) leaves its half-written output's
# hidden .part file: removed when the workflow starts (no job of it runs then; the
# working directory is Snakemake's lock) and, those of dead writers, when a job fails.
onstart:
    remove_stale_parts(["results", "reports"], nothing_runs=True)


onerror:
    remove_stale_parts(["results", "reports"])


include: "workflow/rules/common.smk"


if config["kind"] == "spring_slider":
    # a campaign of spring-slider records: the law fitted on those whose role is fit,
    # predicted on every record (the others are held out: the fit never reads them)
    SLIDERS = read_slider_campaign(config["sliders"]["records"])
    SLIDER_IDS = list(SLIDERS.index)
    SLIDER_FIT_IDS = [i for i in SLIDER_IDS if SLIDERS.loc[i, "role"] == "fit"]

    wildcard_constraints:
        record_id="|".join(map(re.escape, SLIDER_IDS)),

    include: "workflow/rules/slider_ingest.smk"
    include: "workflow/rules/slider_fit.smk"
    include: "workflow/rules/slider_predict.smk"
    include: "workflow/rules/slider_report.smk"

    rule all:
        input:
            "results/sliders/fit.json",
            expand("results/sliders/{record_id}/prediction.json", record_id=SLIDER_IDS),
            "reports/sliders.html",
        default_target: True

else:
    campaign = read_campaign(config["tests"])
    # each row against the table's schema, errors naming the table's line
    check_campaign(config, campaign, load_schema("tests"))
    check_stages(config)

    TEST_IDS = list(campaign["test_id"])
    FILMED_IDS = [test_id for test_id in TEST_IDS if campaign.loc[test_id, "frames"]]
    MAP_JOBS = deal_rows(config["map"]["height_ratios"], config["map"]["row_jobs"])
    MAP_SHARDS = shard_count(friction_grid(*config["map"]["frictions"]), config["map"]["shard_size"])
    # the map at its mesh, and at the coarser mesh its band (where it still moves) is drawn from
    MAP_ELEMENTS, *MAP_BAND_ELEMENTS = map_meshes(
        config["map"]["elements"], config["map"]["band_elements"]
    )

    wildcard_constraints:
        test_id="|".join(map(re.escape, TEST_IDS)) or "no-tests",
        job=r"\d+",
        shard=r"\d+",
        elements=r"\d+",


    include: "workflow/rules/compile.smk"
    include: "workflow/rules/ingest.smk"
    include: "workflow/rules/detect.smk"
    include: "workflow/rules/summary.smk"
    include: "workflow/rules/kymograph.smk"
    include: "workflow/rules/waves.smk"
    include: "workflow/rules/report.smk"
    include: "workflow/rules/campaign_report.smk"
    include: "workflow/rules/map.smk"
    include: "workflow/rules/fit.smk"
    include: "workflow/rules/fits.smk"
    include: "workflow/rules/simulate.smk"
    include: "workflow/rules/simulate_waves.smk"
    include: "workflow/rules/fit_waves.smk"
    include: "workflow/rules/compare.smk"


    rule all:
        input:
            expand("results/{test_id}/recording.nc", test_id=TEST_IDS),
            expand("results/{test_id}/events.csv", test_id=TEST_IDS),
            expand("results/{test_id}/waves.csv", test_id=FILMED_IDS),
            expand("reports/{test_id}.{format}", test_id=TEST_IDS, format=("html", "pdf")),
            "reports/campaign.html",
            "reports/campaign.pdf",
            "results/summary.csv",
            "results/map/map.nc",
            "results/map/map.png",
            *(
                expand("results/{test_id}/comparison.csv", test_id=TEST_IDS)
                + ["results/fits.csv"]
                if config["fit"]["enabled"]
                else []
            ),
        default_target: True
