# Shipped networks: `make models` reproduces data generation, training, export, baselines and
# the mask ceiling of the model card.
# Included from the top Makefile (uses $(VENV) and the `setup` target).
# The dataset and training steps are resumable: an interrupted `make models` continues where
# it stopped. Training refuses a MODELS_TRAIN trained on other data or settings (it records
# both); `rm -rf $(MODELS_TRAIN)` (or `guidance train --restart`) starts it over.
# Override for a quicker run, e.g. `make models MODELS_N_BASE=400`. The default is 2.5 times
# the paper's 1,592 landings: the constraint network's precision at recall 0.99 grows with the
# number of distinct landings (0.53 on 1,592, 0.60 on 4,000). Each model's training is capped
# at MODELS_TRAIN_MINUTES of wall clock; on a 2-core machine only the paper-size constraint
# reference reaches it (the card marks capped models).

MODELS_N_BASE  ?= 4000
MODELS_TRAIN_MINUTES ?= 15
# Subproblem proximal weight of the data (SCvxSettings.prox_u; the shipped networks' data: 0.02)
MODELS_PROX_U  ?= 0.02
MODELS_DATA    ?= data/dataset.npz
MODELS_RUN_DIR ?= data/runs/default
MODELS_TRAIN   ?= data/train

.PHONY: models

models: setup lib $(BUILD)/nn_budget_driver
	nice $(GUIDANCE) dataset --n-base $(MODELS_N_BASE) --prox-u $(MODELS_PROX_U) \
	  --run-dir $(MODELS_RUN_DIR) --output $(MODELS_DATA)
	nice $(GUIDANCE) train --dataset $(MODELS_DATA) --train-dir $(MODELS_TRAIN) --sizes flight-m,flight-mlp,flight-s,reference \
	  --max-minutes $(MODELS_TRAIN_MINUTES)
	$(GUIDANCE) export --train-dir $(MODELS_TRAIN) --dataset $(MODELS_DATA) --models-dir models
	$(GUIDANCE) baselines --dataset $(MODELS_DATA) --models-dir models
	$(GUIDANCE) mask-ceiling --models-dir models
