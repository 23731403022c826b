"""Planners that know the model: exact references over sampled starts (the clairvoyant
bound, the belief-space optimum and its policy, [`crmgrasp.planners.references`][]; the same
policy over other starts, a realizable reference, [`crmgrasp.planners.realizable`][]),
explicit POMDPs ([`crmgrasp.planners.pomdp`][]) and a POMDP built from a task and
solved by point-based value iteration ([`crmgrasp.planners.pomdp_task`][]). Their
policies act through [`crmgrasp.sim.run_episode`][] like every learner."""
