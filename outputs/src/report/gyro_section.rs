//! The report's gyro section: the calibration's `G` and `b` (docs/model.md §8) with the session
//! fit's 1σ, each axis's scale error as every command says it (`estimate::gyro::scale_error`), and
//! how well the corrected gyro reads the table's known rate in each spin (the turns' residuals).

use super::data::ReportData;
use super::page::Block;
use estimator::estimate::SegmentKind;
use shared::params::axis_name;

/// The section's blocks: a heading, `G`/`b` with 1σ, and the spins' residuals (or why none).
pub(crate) fn gyro_section(data: &ReportData) -> Vec<Block> {
    let mut b = vec![Block::Heading(2, "Gyro".into())];
    let Some(gyro) = &data.calibration.gyro else {
        b.push(Block::Para(
            "The calibration has no gyro part: the device takes its gyro as perfect (G = I, b = 0)."
                .into(),
        ));
        return b;
    };
    let fit = data.session_fit.as_ref().ok().and_then(|o| o.gyro.as_ref());
    b.push(Block::Para(
        "w = G·ω + b (docs/model.md §8): G's rows are the gyro axes, its columns the body axes; the \
         scale error is the row's length less one; 1σ from this session's own fit (— where it \
         determines none)."
            .into(),
    ));
    let sd = |f: &dyn Fn(&estimator::estimate::GyroEstimate) -> f64| {
        fit.map_or("—".to_string(), |g| format!("{:.6}", f(g)))
    };
    let zero = [[0.0; 3]; 3];
    let scale = estimator::estimate::gyro::scale_error(
        &gyro.matrix,
        fit.map_or(&zero, |g| &g.matrix_1sigma),
    );
    let rows = (0..3)
        .map(|i| {
            let mut row = vec![axis_name(i).to_string()];
            for j in 0..3 {
                row.push(format!("{:.6}", gyro.matrix[i][j]));
                row.push(sd(&|g| g.matrix_1sigma[i][j]));
            }
            row.push(format!("{:+.0}", scale[i].0 * 1e6));
            row.push(sd(&|g| scale_sigma_ppm(g, i)));
            row.push(format!("{:+.5}", gyro.bias_rad_s[i].to_degrees()));
            row.push(sd(&|g| g.bias_rad_s_1sigma[i].to_degrees()));
            row
        })
        .collect();
    b.push(Block::Table {
        header: [
            "gyro axis",
            "G·x",
            "1σ",
            "G·y",
            "1σ",
            "G·z",
            "1σ",
            "scale error ppm",
            "1σ ppm",
            "b °/s",
            "1σ °/s",
        ]
        .map(String::from)
        .to_vec(),
        rows,
    });
    let spins: Vec<Vec<String>> = data
        .segments
        .iter()
        .filter(|r| r.kind != SegmentKind::Static && r.planned_rate_deg_s != 0.0)
        .map(|r| {
            let omega = r.planned_rate_deg_s;
            let mut row = vec![r.name.clone(), format!("{omega:+.1}")];
            row.extend(
                (0..3)
                    .map(|j| format!("{:+.5}", r.omega_rad_s[j].to_degrees() - omega * r.up_b[j])),
            );
            row
        })
        .collect();
    if spins.is_empty() {
        b.push(Block::Para(
            "No spins at a known rate in this session: a hand-held session's gyro is fitted from \
             its turns by `host segment` (gyro.toml gives its rms misfit)."
                .into(),
        ));
    } else {
        b.push(Block::Para(
            "The turns' residuals: the corrected gyro's mean rate less the table's rate about the \
             mount's up, body axes, °/s."
                .into(),
        ));
        b.push(Block::Table {
            header: ["segment", "table °/s", "x °/s", "y °/s", "z °/s"]
                .map(String::from)
                .to_vec(),
            rows: spins,
        });
    }
    b
}

/// The scale error's 1σ of gyro axis `i`, ppm.
fn scale_sigma_ppm(g: &estimator::estimate::GyroEstimate, i: usize) -> f64 {
    estimator::estimate::gyro::scale_error(&g.matrix, &g.matrix_1sigma)[i].1 * 1e6
}
