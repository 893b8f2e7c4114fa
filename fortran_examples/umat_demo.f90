! umat_demo.f90 -- mesorve from a Fortran host, in the style of an Abaqus/CalculiX UMAT.
!
! 1. A UMAT-shaped routine keeps the RVE handle in a STATEV slot (a double: handles are
!    exact in a double), creates the instance on its first call, commits the previous
!    increment when a new one starts, and is driven along the scene's strain path with two
!    calls per increment, as a host's global Newton would call it: a wrong iterate (half
!    the increment), then the final strain. Only the last trial of an increment is
!    committed. Writes a CSV with the columns of c_examples/rve_driver.c (D11..D33 are
!    ddsdde(i, j) = d s_i / d e_j, row by row). Given a reference CSV (rve_driver's, which
!    equals `rve run`), checks strain, stress, tangent and counters to the last bit, and
!    that the raw tangent array of rve_update_ex is the transpose of the Jacobian.
! 2. One mixed-control macro Newton step (eps_xx prescribed, eps_yy and gamma_xy found so
!    that sig_yy = sig_xy = 0) on a clone of the model, with rve_update_f's ddsdde:
!    quadratic convergence; the elastic tangent, for contrast, needs more iterations.
! 3. Error paths: a missing scene file and a malformed scene text give BAD_SCENE with a
!    message from rve_last_error_f; a solver failure gives SOLVER_FAILED and PNEWDT < 1; a
!    freed handle left in STATEV gives BAD_HANDLE.
!
! Usage: umat_demo [SCENE.toml [OUT.csv [REFERENCE.csv]]]
!        (defaults: scenes/paper_rve_cycle.toml, umat_demo.csv, no reference)
! Exit status 0 when every check passed.
!
! Build: gfortran -c rve.f90 && gfortran umat_demo.f90 rve.o -lrve   (plus -L, rpath)

module demo_support
  use rve
  use, intrinsic :: iso_fortran_env, only: error_unit
  implicit none
  private
  public :: expect, expect_status, same_bits, num, read_text, replace, umat
  public :: checks, failures

  integer, save :: checks = 0, failures = 0
  ! The increment the RVE of this (single) point last saw. It must live outside STATEV:
  ! Abaqus hands the start-of-increment STATEV back at every iteration.
  integer, save :: seen_kinc = -1

contains

  subroutine expect(ok, what)
    logical, intent(in) :: ok
    character(len=*), intent(in) :: what
    checks = checks + 1
    if (.not. ok) then
      failures = failures + 1
      write (error_unit, '(a)') 'FAILED: ' // what
    end if
  end subroutine expect

  ! Checks a status; on a mismatch prints both codes and the last error message.
  subroutine expect_status(got, want, what)
    integer(c_int32_t), intent(in) :: got, want
    character(len=*), intent(in) :: what
    checks = checks + 1
    if (got /= want) then
      failures = failures + 1
      write (error_unit, '(5a)') 'FAILED: ', what, ': ', rve_status_message_f(got), &
          ' (expected ' // rve_status_message_f(want) // '): ' // rve_last_error_f()
    end if
  end subroutine expect_status

  logical function same_bits(a, b)
    real(c_double), intent(in) :: a, b
    same_bits = transfer(a, 0_c_int64_t) == transfer(b, 0_c_int64_t)
  end function same_bits

  ! A double with 17 significant digits (exact when read back), without blanks.
  function num(x) result(s)
    real(c_double), intent(in) :: x
    character(len=:), allocatable :: s
    character(len=32) :: buf
    write (buf, '(es25.16e3)') x
    s = trim(adjustl(buf))
  end function num

  ! The whole file as one string ("" when it cannot be read).
  function read_text(path) result(text)
    character(len=*), intent(in) :: path
    character(len=:), allocatable :: text
    integer :: u, n, ios
    open (newunit=u, file=path, access='stream', form='unformatted', status='old', &
        action='read', iostat=ios)
    if (ios /= 0) then
      text = ''
      return
    end if
    inquire (unit=u, size=n)
    allocate (character(len=n) :: text)
    read (u, iostat=ios) text
    close (u)
    if (ios /= 0) text = ''
  end function read_text

  ! text with the first `from` replaced by `to` ("" when `from` is absent).
  function replace(text, from, to) result(out)
    character(len=*), intent(in) :: text, from, to
    character(len=:), allocatable :: out
    integer :: at
    at = index(text, from)
    if (at == 0) then
      out = ''
    else
      out = text(:at - 1) // to // text(at + len(from):)
    end if
  end function replace

  ! A UMAT-shaped material routine for one integration point (Abaqus argument names; NTENS
  ! = 3 components [11, 22, 12] with engineering shear, plane stress or plane strain as the
  ! scene says).
  !   statev(1)  the RVE handle as a double (0 before the first call)
  !   stran      total strain at the start of the increment; dstran its increment
  !   kinc       the increment number (KINC)
  !   ddsdde     d stress_i / d strain_j at (i, j)
  !   pnewdt     set to the RVE's suggested ratio when it fails (the host cuts the step)
  ! Trial/commit: every call is a trial from the last committed state; the last trial of
  ! increment KINC is the converged one, so it is committed on the first call of a new
  ! increment. A cut-back increment keeps its number, so a failed attempt is never
  ! committed. `raw` (the C row-major array as Fortran sees it), `info` and `status` are
  ! extra outputs for the demo's checks.
  subroutine umat(stress, statev, ddsdde, stran, dstran, kinc, pnewdt, scene, raw, info, &
      status)
    real(c_double), intent(inout) :: stress(3), statev(:), ddsdde(3, 3), pnewdt
    real(c_double), intent(in) :: stran(3), dstran(3)
    integer, intent(in) :: kinc
    character(len=*), intent(in) :: scene
    real(c_double), intent(inout) :: raw(3, 3)
    type(rve_info), intent(inout) :: info
    integer(c_int32_t), intent(out) :: status
    integer(c_int64_t) :: h
    h = int(statev(1), c_int64_t)
    if (h == 0) then
      status = rve_init_file_f(scene, h)
      if (status /= RVE_STATUS_OK) return
      statev(1) = real(h, c_double)
      seen_kinc = kinc
    else if (kinc /= seen_kinc) then
      status = rve_commit(h)
      if (status /= RVE_STATUS_OK) return
      seen_kinc = kinc
    end if
    status = rve_update_ex(h, stran + dstran, stress, raw, RVE_TANGENT_REQUEST_CONSISTENT, &
        info)
    if (status == RVE_STATUS_OK) then
      ddsdde = transpose(raw)     ! the C array is row-major: Fortran sees the transpose
    else if (status == RVE_STATUS_SOLVER_FAILED) then
      pnewdt = info%suggested_step_ratio
    end if
  end subroutine umat

end module demo_support

program umat_demo
  use rve
  use demo_support
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
  implicit none
  character(len=4096) :: scene, out_csv, ref_csv
  integer(c_int64_t) :: hpath, h
  integer(c_size_t) :: n, i
  integer :: nargs
  real(c_double), allocatable :: path(:, :)

  nargs = command_argument_count()
  scene = 'scenes/paper_rve_cycle.toml'
  out_csv = 'umat_demo.csv'
  ref_csv = ''
  if (nargs >= 1) call get_command_argument(1, scene)
  if (nargs >= 2) call get_command_argument(2, out_csv)
  if (nargs >= 3) call get_command_argument(3, ref_csv)

  write (*, '(3a,i0,a,i0)') 'umat_demo: library ', rve_version_f(), ', ABI ', &
      rve_abi_version(), ', module ABI ', RVE_MODULE_ABI_VERSION
  if (rve_abi_version() /= RVE_MODULE_ABI_VERSION) then
    write (*, '(a)') 'umat_demo: the library ABI differs from the module''s'
    stop 1
  end if

  ! The host's loading: here the scene's own strain path, read through a first instance
  ! (kept alive, so every later instance of the scene shares its model).
  hpath = 0
  call expect_status(rve_init_file_f(scene, hpath), RVE_STATUS_OK, 'rve_init_file_f')
  if (hpath == 0) stop 1
  n = 0
  call expect_status(rve_path_len(hpath, n), RVE_STATUS_OK, 'rve_path_len')
  allocate (path(3, 0:n))
  path(:, 0) = 0
  do i = 1, n
    call expect_status(rve_path_point(hpath, i - 1, path(:, i)), RVE_STATUS_OK, &
        'rve_path_point')
  end do
  call expect(n > 0, 'the scene has a strain path')

  call follow_path()
  call macro_newton()
  call error_paths()

  call expect_status(rve_free(hpath), RVE_STATUS_OK, 'rve_free')
  deallocate (path)
  write (*, '(a,i0,a,i0,a)') 'umat_demo: ', checks, ' checks, ', failures, ' failed'
  if (failures > 0) stop 1

contains

  ! Part 1: the UMAT along the path, against the C driver's CSV when given.
  subroutine follow_path()
    real(c_double) :: statev(4), stress(3), ddsdde(3, 3), raw(3, 3), pnewdt, dstran(3)
    real(c_double) :: ref(20)
    type(rve_info) :: info
    integer(c_int32_t) :: st
    integer(c_int64_t) :: builds
    integer :: kinc, u, r, k, ios, ii, jj, mismatches, asymmetric
    logical :: have_ref
    character(len=512) :: header

    statev = 0
    stress = 0
    ddsdde = 0
    raw = 0
    info = rve_info(0, 0, 0, 0, 1.0_c_double, 0.0_c_double)
    builds = rve_model_builds()
    have_ref = len_trim(ref_csv) > 0
    mismatches = 0
    asymmetric = 0
    if (have_ref) then
      open (newunit=r, file=ref_csv, status='old', action='read', iostat=ios)
      call expect(ios == 0, 'open the reference CSV ' // trim(ref_csv))
      if (ios /= 0) stop 1
      read (r, '(a)') header
    end if
    open (newunit=u, file=out_csv, status='replace', action='write')
    write (u, '(a)') 'step,eps_xx,eps_yy,gamma_xy,sig_xx,sig_yy,sig_xy,D11,D12,D13,D21,' // &
        'D22,D23,D31,D32,D33,iterations,substeps,s_zz,factorizations'
    do kinc = 1, int(n)
      dstran = path(:, kinc) - path(:, kinc - 1)
      pnewdt = 1
      ! Host iteration 1: a wrong iterate (half the increment), a trial only.
      call umat(stress, statev, ddsdde, path(:, kinc - 1), 0.5_c_double * dstran, kinc, &
          pnewdt, scene, raw, info, st)
      call expect_status(st, RVE_STATUS_OK, 'umat, first iterate')
      ! Host iteration 2: the converged strain; its trial is the one committed.
      call umat(stress, statev, ddsdde, path(:, kinc - 1), dstran, kinc, pnewdt, scene, &
          raw, info, st)
      call expect_status(st, RVE_STATUS_OK, 'umat')
      if (st /= RVE_STATUS_OK) exit
      if (kinc == 1) then
        ! The handle round-trips through the double STATEV slot, and the UMAT's instance
        ! shares the model of the first one (no new mesh).
        call expect(int(statev(1), c_int64_t) /= 0 .and. same_bits(statev(1), &
            real(int(statev(1), c_int64_t), c_double)), 'handle exact in STATEV')
        call expect(rve_model_builds() == builds, 'instances of one scene share one model')
      end if
      call expect(pnewdt >= 1, 'PNEWDT untouched on success')
      write (u, '(i0,*(a))') kinc, (',' // num(path(k, kinc - 1) + dstran(k)), k = 1, 3), &
          (',' // num(stress(k)), k = 1, 3), &
          ((',' // num(ddsdde(ii, jj)), jj = 1, 3), ii = 1, 3), &
          ',' // itoa(info%iterations), ',' // itoa(info%substeps), ',' // num(info%s_zz), &
          ',' // itoa(info%factorizations)
      if (have_ref) then
        read (r, *, iostat=ios) ref
        call expect(ios == 0, 'read a reference row')
        if (ios /= 0) exit
        ! Columns: step, eps(3), sig(3), D11..D33 row-major (C), 4 counters.
        do k = 1, 3
          if (.not. same_bits(path(k, kinc - 1) + dstran(k), ref(1 + k))) &
              mismatches = mismatches + 1
          if (.not. same_bits(stress(k), ref(4 + k))) mismatches = mismatches + 1
        end do
        do ii = 1, 3
          do jj = 1, 3
            ! UMAT orientation: ddsdde(i, j) = C's tangent[3*i + j].
            if (.not. same_bits(ddsdde(ii, jj), ref(7 + 3 * (ii - 1) + jj))) &
                mismatches = mismatches + 1
            ! The raw array is the transpose: raw(j, i) = C's tangent[3*i + j].
            if (.not. same_bits(raw(jj, ii), ref(7 + 3 * (ii - 1) + jj))) &
                mismatches = mismatches + 1
            if (.not. same_bits(raw(ii, jj), ref(7 + 3 * (ii - 1) + jj))) &
                asymmetric = asymmetric + 1
          end do
        end do
        if (info%iterations /= nint(ref(17)) .or. info%substeps /= nint(ref(18)) .or. &
            .not. same_bits(info%s_zz, ref(19)) .or. &
            info%factorizations /= nint(ref(20))) mismatches = mismatches + 1
        if (mismatches > 0) then
          write (*, '(a,i0,a,i0,a)') 'increment ', kinc, ': ', mismatches, &
              ' values differ from the reference'
          call expect(.false., 'bit-identical to the C driver')
          exit
        end if
      end if
    end do
    close (u)
    ! Accept the last increment (a host's end-of-increment hook would do this), then free.
    h = int(statev(1), c_int64_t)
    call expect_status(rve_commit(h), RVE_STATUS_OK, 'rve_commit of the last increment')
    call expect_status(rve_free(h), RVE_STATUS_OK, 'rve_free')
    if (have_ref) then
      read (r, *, iostat=ios) ref
      call expect(ios /= 0, 'the reference has no more rows than the path')
      close (r)
      if (mismatches == 0) then
        write (*, '(a,i0,a)') 'part 1: ', n, ' increments bit-identical to the C driver ' // &
            '(strain, stress, tangent, counters)'
        write (*, '(a,i0,a)') '        raw tangent = transpose of d s_i / d e_j; ', &
            asymmetric, ' raw entries differ from the untransposed Jacobian'
        if (asymmetric == 0) write (*, '(a)') '        (the tangent was exactly ' // &
            'symmetric: the transpose check saw no difference)'
      end if
    else
      write (*, '(a,i0,a)') 'part 1: ', n, ' increments (no reference CSV: not compared)'
    end if
    write (*, '(2a)') '        wrote ', trim(out_csv)
  end subroutine follow_path

  ! Part 2: one mixed-control macro step from the virgin state: eps_xx = 1.5e-4 (before
  ! the peak, with ITZ damage) is prescribed, eps_yy and gamma_xy start at 0 and are
  ! found by Newton so that sig_yy = sig_xy = 0, with rve_update_f's ddsdde(i, j) =
  ! d s_i / d e_j. With the consistent tangent the relative residual r_k must fall
  ! quadratically, r_k+1 <= 10 r_k^2, until the floor set by the RVE's own tolerance; the
  ! same step with the elastic tangent (a modified Newton) is shown for contrast and must
  ! need more iterations.
  subroutine macro_newton()
    integer, parameter :: max_it = 12
    real(c_double), parameter :: floor = 1e-7_c_double
    real(c_double) :: r(0:max_it), eps(3), sig_xx
    integer :: its, its_elastic, k, rate_checks
    real(c_double) :: worst

    call newton_step(RVE_TANGENT_REQUEST_CONSISTENT, r, its, eps, sig_xx)
    write (*, '(a,es9.2,a)') 'part 2: one mixed-control step to eps_xx = ', eps(1), &
        ', r_k = |[sig_yy, sig_xy]| / |sig_xx|:'
    write (*, '(a,*(es10.2))') '        consistent tangent:', r(0:its)
    rate_checks = 0
    worst = 0
    do k = 1, its
      if (r(k - 1) > floor) then
        rate_checks = rate_checks + 1
        worst = max(worst, r(k) / r(k - 1)**2)
        call expect(r(k) <= 10 * r(k - 1)**2 .or. r(k) <= floor, 'quadratic convergence')
      end if
    end do
    call expect(rate_checks >= 2, 'at least two iterations tested the rate')
    write (*, '(a,i0,a,es9.2,a,3es11.3,a,f7.4)') '        ', rate_checks, &
        ' rate checks, max r_k+1 / r_k^2 = ', worst, '; eps =', eps, ', sig_xx =', sig_xx
    call newton_step(RVE_TANGENT_REQUEST_ELASTIC, r, its_elastic, eps, sig_xx)
    write (*, '(a,*(es10.2))') '        elastic tangent:   ', r(0:min(its_elastic, 8))
    call expect(its_elastic > its, 'the consistent tangent needs fewer iterations')
    write (*, '(a,i0,a,i0,a)') '        ', its, ' iterations with the consistent tangent, ', &
        its_elastic, ' with the elastic one'
  end subroutine macro_newton

  ! Newton iterations of the mixed-control step on a fresh clone of the model; r(0:its)
  ! are the residuals (its = max_it + 1 when it did not converge to 1e-9).
  subroutine newton_step(request, r, its, eps, sig_xx)
    integer(c_int32_t), intent(in) :: request
    real(c_double), intent(out) :: r(0:), eps(3), sig_xx
    integer, intent(out) :: its
    integer(c_int64_t) :: hn
    integer(c_int32_t) :: st
    real(c_double) :: sig(3), d(3, 3), det, de2, de3
    integer :: k

    hn = 0
    call expect_status(rve_clone_model(hpath, hn), RVE_STATUS_OK, 'rve_clone_model')
    eps = [1.5e-4_c_double, 0.0_c_double, 0.0_c_double]
    sig = 0
    d = 0
    r = 0
    its = ubound(r, 1) + 1
    do k = 0, ubound(r, 1)
      st = rve_update_f(hn, eps, sig, d, request)
      call expect_status(st, RVE_STATUS_OK, 'rve_update_f')
      if (st /= RVE_STATUS_OK) exit
      r(k) = sqrt(sig(2)**2 + sig(3)**2) / abs(sig(1))
      if (r(k) < 1e-9_c_double) then
        its = k
        exit
      end if
      ! Solve [D22 D23; D32 D33] [de_yy; dg_xy] = -[sig_yy; sig_xy], D(i,j) = ds_i/de_j.
      det = d(2, 2) * d(3, 3) - d(2, 3) * d(3, 2)
      de2 = (-sig(2) * d(3, 3) + sig(3) * d(2, 3)) / det
      de3 = (-sig(3) * d(2, 2) + sig(2) * d(3, 2)) / det
      eps(2) = eps(2) + de2
      eps(3) = eps(3) + de3
    end do
    sig_xx = sig(1)
    if (request == RVE_TANGENT_REQUEST_CONSISTENT) then
      call expect(its <= 5, 'the step converges in at most 5 iterations')
      call expect_status(rve_commit(hn), RVE_STATUS_OK, 'rve_commit')
    end if
    call expect_status(rve_free(hn), RVE_STATUS_OK, 'rve_free')
  end subroutine newton_step

  ! Part 3: what a host sees when things go wrong.
  subroutine error_paths()
    integer(c_int64_t) :: hb, weak
    integer(c_int32_t) :: st
    real(c_double) :: statev(4), stress(3), ddsdde(3, 3), raw(3, 3), pnewdt, bad(3)
    character(len=:), allocatable :: text, msg
    type(rve_info) :: info
    integer :: before

    ! A missing scene: the UMAT's first call fails; STATEV stays 0; a readable message.
    statev = 0
    stress = 7
    pnewdt = 1
    before = failures
    call umat(stress, statev, ddsdde, [0.0_c_double, 0.0_c_double, 0.0_c_double], &
        [1e-5_c_double, 0.0_c_double, 0.0_c_double], 1, pnewdt, '/nonexistent/scene.toml', &
        raw, info, st)
    msg = rve_last_error_f()
    call expect_status(st, RVE_STATUS_BAD_SCENE, 'missing scene file')
    call expect(same_bits(statev(1), 0.0_c_double) .and. same_bits(stress(1), 7.0_c_double), &
        'nothing written on failure')
    call expect(index(msg, '/nonexistent/scene.toml') > 0, 'the message names the file')
    write (*, '(a,i0,3a)') 'part 3: missing scene: status ', st, ' (', &
        rve_status_message_f(st), ')'
    write (*, '(2a)') '        rve_last_error: ', msg

    ! Malformed scene text.
    hb = 777
    st = rve_init_text_f('[cell' // new_line('a') // 'size = ', hb)
    msg = rve_last_error_f()
    call expect_status(st, RVE_STATUS_BAD_SCENE, 'malformed scene text')
    call expect(hb == 777 .and. len(msg) > 0, 'handle untouched, message given')
    write (*, '(2a)') '        malformed text: ', msg
    call expect(len(rve_version_f()) > 0, 'rve_version')
    call expect(rve_last_error_f() == msg, 'version calls keep the last error')

    ! A solver failure: the scene without its fallbacks and with one iteration. PNEWDT < 1,
    ! stress untouched, no trial to commit.
    text = read_text(scene)
    text = replace(text, 'max_iterations = 40', 'max_iterations = 1' // new_line('a') // &
        'path_following = false' // new_line('a') // 'max_secant_iterations = 0' // &
        new_line('a') // 'max_substep_depth = 0')
    if (len(text) == 0) then
      write (*, '(a)') '        (scene has no `max_iterations = 40`: solver failure skipped)'
    else
      weak = 0
      call expect_status(rve_init_text_f(text, weak), RVE_STATUS_OK, 'weak scene')
      info%suggested_step_ratio = 99
      stress = 7
      st = rve_update_ex(weak, [3e-4_c_double, 0.0_c_double, 0.0_c_double], stress, raw, &
          RVE_TANGENT_REQUEST_CONSISTENT, info)
      call expect_status(st, RVE_STATUS_SOLVER_FAILED, 'too large an increment')
      msg = rve_last_error_f()
      pnewdt = info%suggested_step_ratio
      call expect(pnewdt > 0 .and. pnewdt < 1 .and. info%reliability == &
          RVE_RELIABILITY_FAILED .and. same_bits(stress(1), 7.0_c_double), &
          'PNEWDT < 1, stress untouched')
      call expect_status(rve_commit(weak), RVE_STATUS_NO_TRIAL, 'nothing to commit')
      write (*, '(a,f6.3,2a)') '        solver failure: PNEWDT = ', pnewdt, ': ', msg
      call expect_status(rve_free(weak), RVE_STATUS_OK, 'rve_free')
    end if

    ! Bad strains and a bad tangent request on a live instance.
    hb = 0
    call expect_status(rve_clone_model(hpath, hb), RVE_STATUS_OK, 'rve_clone_model')
    bad = [ieee_value(1.0_c_double, ieee_quiet_nan), 0.0_c_double, 0.0_c_double]
    call expect_status(rve_update_f(hb, bad, stress, ddsdde), RVE_STATUS_NON_FINITE_STRAIN, &
        'NaN strain')
    bad = [0.0_c_double, 0.0_c_double, 1e3_c_double]
    call expect_status(rve_update_f(hb, bad, stress, ddsdde), RVE_STATUS_ABSURD_STRAIN, &
        'absurd strain')
    bad = [1e-5_c_double, 0.0_c_double, 0.0_c_double]
    call expect_status(rve_update_f(hb, bad, stress, ddsdde, 3_c_int32_t), &
        RVE_STATUS_INVALID_ARGUMENT, 'unknown tangent request')
    call expect(same_bits(stress(1), 7.0_c_double), 'stress untouched by failed updates')
    call expect_status(rve_commit(hb), RVE_STATUS_NO_TRIAL, 'commit after failures')

    ! A freed handle left in a STATEV slot is refused, never dereferenced.
    statev(1) = real(hb, c_double)
    call expect_status(rve_free(hb), RVE_STATUS_OK, 'rve_free')
    st = rve_update_f(int(statev(1), c_int64_t), bad, stress, ddsdde)
    call expect_status(st, RVE_STATUS_BAD_HANDLE, 'freed handle')
    write (*, '(2a)') '        freed handle: ', rve_last_error_f()
    call expect_status(rve_free(hb), RVE_STATUS_BAD_HANDLE, 'double free')
    call expect(rve_status_message_f(4242_c_int32_t) == 'unknown status code', &
        'unknown status code')
    call expect(failures == before, 'part 3')
  end subroutine error_paths

  function itoa(k) result(s)
    integer(c_int32_t), intent(in) :: k
    character(len=:), allocatable :: s
    character(len=16) :: buf
    write (buf, '(i0)') k
    s = trim(buf)
  end function itoa

end program umat_demo
