from tuning import cli_apf, safety
cli_apf.run("/work/wt-tune12/out/tune_apf_w", train=195, holdout=2000, envs=(5,), target=(5,), grid=3, max_iter=5,
            workers=2, config=safety.SafetyConfig(w_ce=1.0, w_mcte=0.1))
