"""The claims ledger: every stage's claims, validated and concatenated.

Its input is a function of the stage declarations (claim_stages, common.smk), evaluated
when the DAG is built, so this file may be included before or after the stages."""


rule claims:
    """results/claims.csv from results/claims/<stage>.csv of every stage."""
    localrule: True  # on a cluster: the login node (a concatenation)
    input:
        lambda w: expand(results("claims/{stage}.csv"), stage=claim_stages()),
    output:
        report(results("claims.csv"), caption="../report/claims.rst", category="Claims"),
    log:
        log_path("claims"),
    benchmark:
        bench_path("claims"),
    threads: 1
    resources:
        **SMALL,
    script:
        "../scripts/claims_ledger.py"
