# slipwave workflow: friction-bench recordings to answers.
# Run: snakemake --cores 2            (the default campaign of config/config.yaml)
#      snakemake --cores 2 --configfile my_campaign.yaml
from snakemake.utils import min_version, validate

from slipwave.campaign import column_arguments, detection_arguments, read_campaign

min_version("8.10")


configfile: "config/config.yaml"


validate(config, "workflow/schemas/config.schema.json")
tests = read_campaign(config["tests"])
validate(tests, "workflow/schemas/tests.schema.json")
for name in tests["columns"]:
    column_arguments(config, name)  # an unknown column-map name fails here, before any job
for ratio in tests["gross_edge_ratio"]:
    detection_arguments(config, ratio)  # so does a bad detection setting

TEST_IDS = list(tests["test_id"])
FILMED_IDS = [test_id for test_id in TEST_IDS if tests.loc[test_id, "frames"]]


wildcard_constraints:
    test_id="|".join(TEST_IDS) or "no-tests",


include: "workflow/rules/common.smk"
include: "workflow/rules/ingest.smk"
include: "workflow/rules/detect.smk"
include: "workflow/rules/video.smk"
include: "workflow/rules/report.smk"


rule all:
    input:
        expand("results/{test_id}/recording.nc", test_id=TEST_IDS),
        expand("results/{test_id}/events.csv", test_id=TEST_IDS),
        expand("results/{test_id}/waves.csv", test_id=FILMED_IDS),
        expand("reports/{test_id}.html", test_id=TEST_IDS),
        "results/summary.csv",
    default_target: True
