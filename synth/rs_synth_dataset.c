// PLACEHOLDER
typedef int rs_placeholder_rs_synth_dataset;
