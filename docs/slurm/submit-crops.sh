mkdir -p bands
job=$(sbatch --parsable render-crops.sbatch)
sbatch --dependency=afterok:$job --wrap 'tracer merge bands/band-*.exr -o scene.exr'
