! api_check.f90 -- calls every bind(C) interface of module rve and checks the results
! against each other: a binding that compiles and links but passes an argument wrongly
! (value or reference, array layout, width) shows up here. scripts/test-fortran checks the
! declarations against include/rve.h; this checks the calls.
!
! Given the CSV of c_examples/implex_time.c (an IMPL-EX path with non-uniform time
! increments through C's rve_update_timed), it also checks that the host's time increment
! passed through the module gives C's results bit for bit (implex_time):
!  1. rve_update_timed, two calls per increment as a host's Newton makes them (a wrong
!     iterate half-way, then the increment's strain, both with the increment's DTIME),
!     then rve_commit; the second call reuses the increment's factorization
!     (solver.fast_path): at most one factorization per increment (none where the
!     increment carries the last one over: an unloading or closed RVE), none in a second
!     call;
!  2. rve_umat with the Abaqus argument list (NTENS = 3, plane stress, NSTATV = 3,
!     PROPS(1:6) = 0: the scene's values and the consistent tangent, CMNAME
!     PAPER_RVE_HOST_IMPLEX), STATEV reset before every call as CalculiX does; each
!     increment is called with STRAN = the last increment's strain, DSTRAN = the step,
!     TIME(2) = the increment's start and DTIME: at every fourth increment first an attempt
!     with twice the step and twice the DTIME that the host cuts back (same KINC, smaller
!     DTIME: the library reverts it), then a wrong iterate half-way and the increment's
!     strain. The library commits an increment at the first call of the next.
! Stress and tangent (DDSDDE(i, j) = d s_i / d e_j = C's tangent[3 (i - 1) + j - 1]) must
! equal C's bit for bit. The inputs are exact: the path's strains and times are small
! integers times powers of two, so STRAN + DSTRAN, the half-way and doubled strains and
! TIME + DTIME are exact.
!
! Usage: api_check [SCENE_DIR [IMPLEX.csv]]   (default: scenes; uses SCENE_DIR/paper_rve.toml
!        and, with IMPLEX.csv, SCENE_DIR/paper_rve_host_implex.toml, found by the UMAT
!        through MESORVE_SCENE_PATH=SCENE_DIR)
! Exit status 0 when every check passed.
program api_check
  use rve
  use, intrinsic :: iso_c_binding, only: c_associated, c_null_ptr
  use, intrinsic :: iso_fortran_env, only: error_unit
  implicit none
  integer :: checks = 0, failures = 0
  character(len=4096) :: dir
  character(len=:), allocatable :: scene, text
  integer(c_int64_t) :: h, h2, h3, builds
  real(c_double), parameter :: eps1(3) = [6.0e-5_c_double, 1.0e-5_c_double, 2.0e-5_c_double]
  real(c_double), parameter :: eps2(3) = [1.2e-4_c_double, 2.0e-5_c_double, -1.0e-5_c_double]

  dir = 'scenes'
  if (command_argument_count() >= 1) call get_command_argument(1, dir)
  scene = trim(dir) // '/paper_rve.toml'

  call versions()
  text = read_text(scene)
  call expect(len(text) > 0, 'read ' // scene)

  ! rve_init_text through the raw interface (NUL-terminated arrays), then a second model
  ! built from the file: the text and the file are distinct cache keys.
  builds = rve_model_builds()
  h = 0
  call expect_status(rve_init_text(text // c_null_char, trim(dir) // c_null_char, h), &
      RVE_STATUS_OK, 'rve_init_text')
  call expect(rve_model_builds() == builds + 1, 'rve_model_builds counts the new model')
  h2 = 0
  call expect_status(rve_clone_model(h, h2), RVE_STATUS_OK, 'rve_clone_model')
  h3 = 0
  call expect_status(rve_clone_model(h, h3), RVE_STATUS_OK, 'rve_clone_model')
  call expect(rve_model_builds() == builds + 1, 'clones share the model')
  call expect(h /= 0 .and. h2 /= 0 .and. h3 /= 0 .and. h /= h2 .and. h2 /= h3, &
      'distinct non-zero handles')

  call updates()
  call init_embedded()
  call trial_semantics()
  call state_bytes()
  call batch()
  call last_error_raw()
  call write_vtk()
  if (command_argument_count() >= 2) call implex_time()

  call expect_status(rve_free(h), RVE_STATUS_OK, 'rve_free')
  call expect_status(rve_free(h2), RVE_STATUS_OK, 'rve_free')
  call expect_status(rve_free(h3), RVE_STATUS_OK, 'rve_free')
  call expect_status(rve_free(0_c_int64_t), RVE_STATUS_OK, 'rve_free(0)')
  deallocate (scene, text)   ! main-program allocatables are not freed at the end
  write (*, '(a,i0,a,i0,a)') 'api_check: ', checks, ' checks, ', failures, ' failed'
  if (failures > 0) stop 1

contains

  subroutine versions()
    type(c_ptr) :: p
    call expect(rve_version_number() == 10000 * RVE_VERSION_MAJOR + 100 * RVE_VERSION_MINOR &
        + RVE_VERSION_PATCH, 'rve_version_number')
    call expect(rve_version_f() == RVE_MODULE_VERSION, 'rve_version = RVE_MODULE_VERSION')
    call expect(rve_abi_version() == RVE_MODULE_ABI_VERSION, 'rve_abi_version')
    p = rve_version()
    call expect(c_associated(p), 'rve_version is not NULL')
    p = rve_status_message(RVE_STATUS_PANIC)
    call expect(c_associated(p), 'rve_status_message is not NULL')
    call expect(rve_status_message_f(RVE_STATUS_OK) /= rve_status_message_f(RVE_STATUS_PANIC), &
        'distinct status messages')
    call expect(rve_status_message_f(4242_c_int32_t) == 'unknown status code', &
        'unknown status code')
  end subroutine versions

  ! rve_update, rve_update_ex and rve_update_f agree; the tangent requests.
  subroutine updates()
    real(c_double) :: s1(3), s2(3), s3(3), d1(3, 3), d2(3, 3), d3(3, 3), e1(3, 3), e2(3, 3)
    real(c_double) :: s4(3), d4(3, 3)
    type(rve_info) :: info
    s1 = 0; s2 = 0; s3 = 0; d1 = 0; d2 = 0; d3 = 0; e1 = 0; e2 = 0; s4 = 0; d4 = 0
    info = rve_info(0, 0, 0, 0, 0.0_c_double, -1.0_c_double)
    call expect_status(rve_update(h, eps1, s1, d1, RVE_TANGENT_REQUEST_CONSISTENT), &
        RVE_STATUS_OK, 'rve_update')
    call expect_status(rve_update_ex(h, eps1, s2, d2, RVE_TANGENT_REQUEST_CONSISTENT, info), &
        RVE_STATUS_OK, 'rve_update_ex')
    call expect_status(rve_update_f(h, eps1, s3, d3), RVE_STATUS_OK, 'rve_update_f')
    call expect(all_bits(s1, s2) .and. all_bits(s1, s3), 'the three updates give one stress')
    call expect(all_bits(reshape(d1, [9]), reshape(d2, [9])), 'rve_update = rve_update_ex')
    ! This scene is integrated implicitly: the time increment changes nothing.
    call expect_status(rve_update_timed(h, eps1, 0.5_c_double, s4, d4, &
        RVE_TANGENT_REQUEST_CONSISTENT, info), RVE_STATUS_OK, 'rve_update_timed')
    call expect(all_bits(s1, s4) .and. all_bits(reshape(d1, [9]), reshape(d4, [9])), &
        'rve_update_timed = rve_update on an implicit scene')
    call expect(all_bits(reshape(d3, [9]), reshape(transpose(d1), [9])), &
        'rve_update_f returns the transpose of the raw array')
    call expect(info%iterations >= 1 .and. info%substeps >= 1 .and. &
        info%factorizations >= 1 .and. info%reliability /= RVE_RELIABILITY_FAILED .and. &
        same_bits(info%suggested_step_ratio, 1.0_c_double) .and. &
        same_bits(info%s_zz, 0.0_c_double), 'rve_info fields (plane stress: s_zz = 0)')
    ! The row-major layout: tangent[3*i + j] = d s_i / d e_j. Check one column by finite
    ! differences in eps_xx (secant, so only roughly): d s / d e_xx is d3(:, 1).
    call expect_status(rve_update(h, eps1 + [1e-9_c_double, 0.0_c_double, 0.0_c_double], &
        s2, d2, RVE_TANGENT_REQUEST_NONE), RVE_STATUS_OK, 'rve_update, NONE')
    call expect(maxval(abs((s2 - s1) / 1e-9_c_double - d3(:, 1))) < 1e-3_c_double * &
        maxval(abs(d3)), 'ddsdde(:, 1) = d stress / d eps_xx (finite difference)')
    ! NONE leaves the tangent alone; ELASTIC is the model's, the same at every strain.
    d2 = 7
    call expect_status(rve_update(h, eps2, s2, d2, RVE_TANGENT_REQUEST_NONE), RVE_STATUS_OK, &
        'rve_update, NONE')
    call expect(all(abs(d2 - 7) < tiny(1.0_c_double)), 'NONE does not write the tangent')
    call expect_status(rve_update(h, eps1, s2, e1, RVE_TANGENT_REQUEST_ELASTIC), &
        RVE_STATUS_OK, 'rve_update, ELASTIC')
    call expect_status(rve_update(h2, eps2, s2, e2, RVE_TANGENT_REQUEST_ELASTIC), &
        RVE_STATUS_OK, 'rve_update, ELASTIC')
    call expect(all_bits(reshape(e1, [9]), reshape(e2, [9])), 'one elastic tangent')
    call expect_status(rve_revert(h), RVE_STATUS_OK, 'rve_revert')
    call expect_status(rve_revert(h2), RVE_STATUS_OK, 'rve_revert')
  end subroutine updates

  ! rve_init: NULL (c_null_ptr; rve_init_f without a path) is the embedded paper RVE, the
  ! scene of paper_rve.toml, so it answers eps1 as h does; a path is rve_init_file.
  subroutine init_embedded()
    integer(c_int64_t) :: he, hf, hraw, untouched
    integer(c_int64_t) :: before
    real(c_double) :: s0(3), s1(3), s2(3), d(3, 3)
    s0 = 0; s1 = 0; s2 = 0; d = 0
    he = 0; hf = 0; hraw = 0; untouched = 777
    call expect_status(rve_update(h, eps1, s0, d, RVE_TANGENT_REQUEST_NONE), RVE_STATUS_OK, &
        'rve_update')
    call expect_status(rve_revert(h), RVE_STATUS_OK, 'rve_revert')
    before = rve_model_builds()
    call expect_status(rve_init_f(handle=he), RVE_STATUS_OK, 'rve_init_f (embedded)')
    call expect_status(rve_init(c_null_ptr, hraw), RVE_STATUS_OK, 'rve_init(c_null_ptr)')
    call expect(rve_model_builds() == before + 1, 'embedded instances share one model')
    call expect_status(rve_init_f(scene, hf), RVE_STATUS_OK, 'rve_init_f (path)')
    call expect_status(rve_update(he, eps1, s1, d, RVE_TANGENT_REQUEST_NONE), RVE_STATUS_OK, &
        'rve_update (embedded)')
    call expect_status(rve_update(hf, eps1, s2, d, RVE_TANGENT_REQUEST_NONE), RVE_STATUS_OK, &
        'rve_update (path)')
    call expect(all_bits(s0, s1) .and. all_bits(s0, s2), &
        'rve_init: embedded scene and path answer as paper_rve.toml')
    call expect_status(rve_init_f(trim(dir) // '/no_such_scene.toml', untouched), &
        RVE_STATUS_BAD_SCENE, 'rve_init_f (missing file)')
    call expect(untouched == 777, 'no handle written on failure')
    call expect_status(rve_free(he), RVE_STATUS_OK, 'rve_free')
    call expect_status(rve_free(hraw), RVE_STATUS_OK, 'rve_free')
    call expect_status(rve_free(hf), RVE_STATUS_OK, 'rve_free')
  end subroutine init_embedded

  ! Trials do not change the committed state; revert and reset.
  subroutine trial_semantics()
    real(c_double) :: s1(3), s2(3), d(3, 3)
    s1 = 0; s2 = 0; d = 0
    call expect_status(rve_update(h, eps2, s1, d, RVE_TANGENT_REQUEST_NONE), RVE_STATUS_OK, &
        'rve_update')
    call expect_status(rve_update(h, eps1, s2, d, RVE_TANGENT_REQUEST_NONE), RVE_STATUS_OK, &
        'rve_update')
    call expect_status(rve_update(h, eps2, s2, d, RVE_TANGENT_REQUEST_NONE), RVE_STATUS_OK, &
        'rve_update')
    call expect(all_bits(s1, s2), 'a trial repeated gives the same bits')
    call expect_status(rve_revert(h), RVE_STATUS_OK, 'rve_revert')
    call expect_status(rve_commit(h), RVE_STATUS_NO_TRIAL, 'commit after revert')
    ! Commit at eps1 on h3, reset it, and it is virgin again: eps2 as on a virgin clone.
    call expect_status(rve_update(h3, eps1, s2, d, RVE_TANGENT_REQUEST_NONE), RVE_STATUS_OK, &
        'rve_update')
    call expect_status(rve_commit(h3), RVE_STATUS_OK, 'rve_commit')
    call expect_status(rve_reset(h3), RVE_STATUS_OK, 'rve_reset')
    call expect_status(rve_update(h3, eps2, s2, d, RVE_TANGENT_REQUEST_NONE), RVE_STATUS_OK, &
        'rve_update')
    call expect(all_bits(s1, s2), 'rve_reset returns to the virgin state')
    call expect_status(rve_revert(h3), RVE_STATUS_OK, 'rve_revert')
  end subroutine trial_semantics

  ! Checkpoint/restart through state bytes.
  subroutine state_bytes()
    integer(c_size_t) :: size, written, n
    integer(c_int8_t), allocatable :: bytes(:)
    real(c_double) :: s1(3), s2(3), d1(3, 3), d2(3, 3), e(3)
    s1 = 0; s2 = 0; d1 = 0; d2 = 0; e = 0
    size = 0
    call expect_status(rve_update(h, eps1, s1, d1, RVE_TANGENT_REQUEST_NONE), RVE_STATUS_OK, &
        'rve_update')
    call expect_status(rve_commit(h), RVE_STATUS_OK, 'rve_commit')
    call expect_status(rve_state_size(h, size), RVE_STATUS_OK, 'rve_state_size')
    call expect(size > 0, 'state size > 0')
    allocate (bytes(size))
    written = 0
    call expect_status(rve_state_save(h, bytes, size - 1, written), &
        RVE_STATUS_BUFFER_TOO_SMALL, 'rve_state_save, short buffer')
    call expect(written == size, 'required size reported')
    written = 0
    call expect_status(rve_state_save(h, bytes, size, written), RVE_STATUS_OK, &
        'rve_state_save')
    call expect(written == size, 'all bytes written')
    call expect_status(rve_state_load(h2, bytes, size), RVE_STATUS_OK, 'rve_state_load')
    call expect_status(rve_state_load(h2, bytes, size / 2), RVE_STATUS_BAD_STATE, &
        'rve_state_load, truncated')
    call expect_status(rve_update(h, eps2, s1, d1, RVE_TANGENT_REQUEST_CONSISTENT), &
        RVE_STATUS_OK, 'rve_update')
    call expect_status(rve_update(h2, eps2, s2, d2, RVE_TANGENT_REQUEST_CONSISTENT), &
        RVE_STATUS_OK, 'rve_update')
    call expect(all_bits(s1, s2) .and. all_bits(reshape(d1, [9]), reshape(d2, [9])), &
        'the restored instance continues bit for bit')
    call expect_status(rve_revert(h), RVE_STATUS_OK, 'rve_revert')
    call expect_status(rve_revert(h2), RVE_STATUS_OK, 'rve_revert')
    n = 0
    call expect_status(rve_path_len(h, n), RVE_STATUS_OK, 'rve_path_len')
    if (n > 0) then
      call expect_status(rve_path_point(h, n - 1, e), RVE_STATUS_OK, 'rve_path_point')
      call expect(any(abs(e) > 0), 'last path point is not zero')
    end if
    call expect_status(rve_path_point(h, n, e), RVE_STATUS_INVALID_ARGUMENT, &
        'rve_path_point past the end')
  end subroutine state_bytes

  ! rve_update_batch on two threads equals single updates; a foreign handle fails alone.
  subroutine batch()
    integer(c_int64_t) :: handles(2)
    real(c_double) :: strains(3, 2), stresses(3, 2), tangents(3, 3, 2), s(3), d(3, 3)
    integer(c_int32_t) :: statuses(2)
    integer :: k
    handles = [h, h2]
    strains(:, 1) = eps1
    strains(:, 2) = eps2
    stresses = 0; tangents = 0; statuses = -1; s = 0; d = 0
    call expect_status(rve_update_batch(handles, 2_c_size_t, strains, stresses, tangents, &
        statuses, RVE_TANGENT_REQUEST_CONSISTENT, 2_c_size_t), RVE_STATUS_OK, &
        'rve_update_batch')
    do k = 1, 2
      call expect(statuses(k) == RVE_STATUS_OK, 'batch item status')
      call expect_status(rve_update(handles(k), strains(:, k), s, d, &
          RVE_TANGENT_REQUEST_CONSISTENT), RVE_STATUS_OK, 'rve_update')
      call expect(all_bits(s, stresses(:, k)) .and. &
          all_bits(reshape(d, [9]), reshape(tangents(:, :, k), [9])), &
          'batch item = rve_update, bit for bit')
    end do
    handles(2) = 999
    statuses = -1
    call expect_status(rve_update_batch(handles, 2_c_size_t, strains, stresses, tangents, &
        statuses, RVE_TANGENT_REQUEST_NONE, 1_c_size_t), RVE_STATUS_BATCH_FAILED, &
        'rve_update_batch with a foreign handle')
    call expect(statuses(1) == RVE_STATUS_OK .and. statuses(2) == RVE_STATUS_BAD_HANDLE, &
        'batch statuses')
    call expect_status(rve_revert(h), RVE_STATUS_OK, 'rve_revert')
    call expect_status(rve_revert(h2), RVE_STATUS_OK, 'rve_revert')
  end subroutine batch

  ! rve_write_vtk: the committed state to a file; unwritable path and freed handle.
  subroutine write_vtk()
    character(len=*), parameter :: file = 'api_check_state.vtu'
    logical :: exists
    integer :: unit, ios
    call expect_status(rve_write_vtk(h, file // c_null_char), RVE_STATUS_OK, 'rve_write_vtk')
    inquire(file=file, exist=exists)
    call expect(exists, 'rve_write_vtk wrote the file')
    if (exists) then
      open(newunit=unit, file=file, status='old', iostat=ios)
      if (ios == 0) close(unit, status='delete')
    end if
    call expect_status(rve_write_vtk(h, '/nonexistent/dir/state.vtu' // c_null_char), &
        RVE_STATUS_WRITE_FAILED, 'rve_write_vtk to a missing directory')
    call expect(len(rve_last_error_f()) > 0, 'rve_write_vtk failure has a message')
    call expect_status(rve_write_vtk(0_c_int64_t, file // c_null_char), &
        RVE_STATUS_BAD_HANDLE, 'rve_write_vtk(0)')
  end subroutine write_vtk

  ! The raw rve_last_error: length query, truncation with a NUL.
  subroutine last_error_raw()
    character(kind=c_char) :: small(8), probe(1)
    integer(c_size_t) :: n, m
    character(len=:), allocatable :: full
    call expect_status(rve_commit(h), RVE_STATUS_NO_TRIAL, 'rve_commit without a trial')
    n = rve_last_error(probe, 0_c_size_t)
    full = rve_last_error_f()
    call expect(n > 8 .and. len(full) == n, 'rve_last_error length')
    small = 'x'
    m = rve_last_error(small, 8_c_size_t)
    call expect(m == n .and. small(8) == c_null_char .and. small(1) == full(1:1) .and. &
        small(7) == full(7:7), 'rve_last_error truncates with a NUL')
    call expect_status(rve_free(h3), RVE_STATUS_OK, 'rve_free')
    call expect(len(rve_last_error_f()) == 0, 'no message after a success')
    h3 = 0
  end subroutine last_error_raw

  ! The host's time increment through the module against C's rve_update_timed (see the
  ! header). The CSV's columns: step, time, dtime, strain(3), stress(3), D11..D33 (C,
  ! row-major), iterations, substeps, factorizations.
  subroutine implex_time()
    character(len=4096) :: csv
    real(c_double), allocatable :: ref(:, :)
    call get_command_argument(2, csv)
    ref = read_csv(trim(csv), 21)
    call expect(size(ref, 2) > 0, 'rows in ' // trim(csv))
    call implex_module(ref, trim(dir) // '/paper_rve_host_implex.toml')
    call implex_umat(ref, 'PAPER_RVE_HOST_IMPLEX')
  end subroutine implex_time

  ! A CSV of numbers after one header line: row k in table(:, k). No rows when the file
  ! cannot be read.
  function read_csv(path, cols) result(table)
    character(len=*), intent(in) :: path
    integer, intent(in) :: cols
    real(c_double), allocatable :: table(:, :)
    real(c_double) :: row(cols)
    integer :: u, ios, rows
    allocate (table(cols, 0))
    open (newunit=u, file=path, status='old', action='read', iostat=ios)
    if (ios /= 0) return
    read (u, *, iostat=ios)             ! the header
    rows = 0
    do while (ios == 0)
      read (u, *, iostat=ios) row
      if (ios == 0) then
        table = reshape([table, row], [cols, rows + 1])
        rows = rows + 1
      end if
    end do
    close (u)
  end function read_csv

  ! Stress and tangent (d(i, j) = d s_i / d e_j) against row k of C's results.
  logical function matches(ref, k, stress, d)
    real(c_double), intent(in) :: ref(:, :), stress(3), d(3, 3)
    integer, intent(in) :: k
    matches = all_bits(stress, ref(7:9, k)) .and. &
        all_bits(reshape(transpose(d), [9]), ref(10:18, k))
  end function matches

  ! Part 1: rve_update_timed, a wrong iterate then the increment's strain.
  subroutine implex_module(ref, path)
    real(c_double), intent(in) :: ref(:, :)
    character(len=*), intent(in) :: path
    integer(c_int64_t) :: hi
    integer(c_int32_t) :: st
    real(c_double) :: last(3), eps(3), stress(3), raw(3, 3), d(3, 3)
    type(rve_info) :: info
    integer :: k, factorizations, most, second
    logical :: ok
    hi = 0
    call expect_status(rve_init_file_f(path, hi), RVE_STATUS_OK, 'rve_init_file_f ' // path)
    last = 0; ok = hi /= 0; factorizations = 0; most = 0; second = 0
    do k = 1, size(ref, 2)
      eps = ref(4:6, k)
      st = rve_update_timed(hi, 0.5_c_double * (last + eps), ref(3, k), stress, raw, &
          RVE_TANGENT_REQUEST_CONSISTENT, info)
      factorizations = factorizations + int(info%factorizations)
      most = max(most, int(info%factorizations))
      ok = ok .and. st == RVE_STATUS_OK
      st = rve_update_timed(hi, eps, ref(3, k), stress, raw, RVE_TANGENT_REQUEST_CONSISTENT, &
          info)
      factorizations = factorizations + int(info%factorizations)
      second = second + int(info%factorizations)
      d = transpose(raw)       ! raw holds C's row-major array
      ok = ok .and. st == RVE_STATUS_OK .and. matches(ref, k, stress, d)
      st = rve_commit(hi)
      ok = ok .and. st == RVE_STATUS_OK
      last = eps
    end do
    call expect(ok, 'implex: rve_update_timed equals C''s results bit for bit')
    call expect(most == 1 .and. second == 0 .and. factorizations <= size(ref, 2), &
        'implex: at most one factorization per increment, none in its second call')
    call expect_status(rve_free(hi), RVE_STATUS_OK, 'rve_free')
    write (*, '(a,i0,a,i0,2a)') 'implex, module rve_update_timed: ', size(ref, 2), &
        ' increments (2 calls each, ', factorizations, ' factorizations) ', verdict(ok)
  end subroutine implex_module

  ! One rve_umat call for point NOEL = 1 of material `name` (NTENS = 3).
  subroutine call_umat(name, stran, dstran, time, dtime, kinc, stress, ddsdde, pnewdt)
    character(len=*), intent(in) :: name
    real(c_double), intent(in) :: stran(3), dstran(3), time(2), dtime
    integer, intent(in) :: kinc
    real(c_double), intent(inout) :: stress(3), ddsdde(3, 3), pnewdt
    character(len=80) :: cmname
    real(c_double) :: statev(3), props(6), sse, spd, scd, rpl, ddsddt(3), drplde(3)
    real(c_double) :: drpldt, predef(1), dpred(1), coords(3), rot(3, 3)
    cmname = name
    statev = 0; props = 0; sse = 0; spd = 0; scd = 0; rpl = 0; ddsddt = 0; drplde = 0
    drpldt = 0; predef = 0; dpred = 0; coords = 0
    rot = reshape([1, 0, 0, 0, 1, 0, 0, 0, 1], [3, 3])
    call rve_umat(stress, statev, ddsdde, sse, spd, scd, rpl, ddsddt, drplde, drpldt, &
        stran, dstran, time, dtime, 20.0_c_double, 0.0_c_double, predef, dpred, cmname, &
        2, 1, 3, 3, props, 6, coords, rot, pnewdt, 1.0_c_double, rot, rot, 1, 1, 0, 0, 1, &
        kinc, len(cmname, c_size_t))
  end subroutine call_umat

  ! Part 2: rve_umat with DTIME, cut-backs and wrong iterates.
  subroutine implex_umat(ref, name)
    real(c_double), intent(in) :: ref(:, :)
    character(len=*), intent(in) :: name
    real(c_double) :: stran(3), eps(3), stress(3), ddsdde(3, 3), pnewdt, time(2), dt
    integer :: k, cuts
    logical :: ok
    stran = 0; ok = .true.; cuts = 0
    do k = 1, size(ref, 2)
      eps = ref(4:6, k); dt = ref(3, k)
      time = ref(2, k) - dt
      pnewdt = 1e36_c_double
      if (mod(k, 4) == 3) then
        call call_umat(name, stran, 2 * (eps - stran), time, 2 * dt, k, stress, ddsdde, pnewdt)
        cuts = cuts + 1
      end if
      call call_umat(name, stran, 0.5_c_double * (eps - stran), time, dt, k, stress, ddsdde, &
          pnewdt)
      call call_umat(name, stran, eps - stran, time, dt, k, stress, ddsdde, pnewdt)
      ok = ok .and. pnewdt > 1 .and. matches(ref, k, stress, ddsdde)
      stran = eps
    end do
    call expect(ok, 'implex: rve_umat''s STRESS and DDSDDE equal C''s bit for bit')
    write (*, '(a,i0,a,i0,2a)') 'implex, rve_umat with DTIME: ', size(ref, 2), &
        ' increments (', cuts, ' cut back) ', verdict(ok)
  end subroutine implex_umat

  function verdict(ok) result(s)
    logical, intent(in) :: ok
    character(len=:), allocatable :: s
    s = 'DIFFERENT from C'
    if (ok) s = 'bit-identical to C'
  end function verdict

  subroutine expect(ok, what)
    logical, intent(in) :: ok
    character(len=*), intent(in) :: what
    checks = checks + 1
    if (.not. ok) then
      failures = failures + 1
      write (error_unit, '(a)') 'FAILED: ' // what
    end if
  end subroutine expect

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

  logical function all_bits(a, b)
    real(c_double), intent(in) :: a(:), b(:)
    integer :: k
    all_bits = size(a) == size(b)
    do k = 1, min(size(a), size(b))
      all_bits = all_bits .and. same_bits(a(k), b(k))
    end do
  end function all_bits

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

end program api_check
