mkdir -p parts
job=$(sbatch --parsable render.sbatch)
sbatch --dependency=afterok:$job --wrap 'tracer merge parts/part-*.exr -o scene.exr'
